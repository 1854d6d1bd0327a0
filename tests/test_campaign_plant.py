"""Campaigns take the arm and plant options of `rc3r run` (--payload, --friction, --torque-limit, ...),
hand them to every job through its configuration, and record each run's verdict in runs.csv."""
from __future__ import annotations

import json

from rc3r.campaign.runner import read_rows
from rc3r.cli import main


def test_montecarlo_with_plant_options_records_verdicts(tmp_path, capsys):
    out = tmp_path / "mc"
    code = main(["montecarlo", "--n", "2", "--controllers", "fbl", "--duration", "0.2", "--rate", "1000",
                 "--friction", "2:0.5", "--torque-limit", "400", "--tolerance", "0.05", "--workers", "1",
                 "--out", str(out)])
    assert code == 0, capsys.readouterr().err
    rows = read_rows(out / "runs.csv")
    assert len(rows) == 2 and all(r["verdict"] in ("clean", "saturated", "chattering") for r in rows)
    assert all(isinstance(r["tolerance_met"], bool) for r in rows)
    assert all(r["saturation_fraction"] is not None for r in rows)  # the torque limit reached the plants
    request = json.loads((out / "summary.json").read_text())["request"]
    assert request["config"]["plant"] == {"friction": "2.0:0.5", "torque_limit": 400.0}
    assert request["config"]["tolerance"] == 0.05
