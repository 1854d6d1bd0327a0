"""Simulation engines: the contract and registry (:mod:`.base`), the compiled engine's integrators
written once for any n and p (:mod:`.compiled`) and the kernel supply they are written against
(:mod:`._template`)."""
from __future__ import annotations

from .base import ENGINES, Engine, choose, engine_names, get_engine, register_engine

__all__ = ["Engine", "ENGINES", "register_engine", "get_engine", "choose", "engine_names"]
