"""Identification: an arm's coefficients, their uncertainty and bounds for the robust laws, from logs."""
