"""The validation study runs end to end on a tiny configuration and writes a readable report."""
import csv
from dataclasses import replace

import pytest

from weather_mi.cli import main
from weather_mi.study import CONFIGS, METRIC_KEYS, run


def test_study_end_to_end_tiny(tmp_path):
    report = run(tmp_path, CONFIGS["tiny"], progress=False)
    text = report.read_text()
    for section in ("The reference and its noise", "Table IV modes", "Convergence", "figure pairs", "Calibration",
                    "Time against error", "misses"):
        assert section in text
    with open(tmp_path / "metrics.csv") as f:
        rows = list(csv.DictReader(f))
    modes = {r["mode"] for r in rows}
    assert {"uniform/low-albedo", "uniform/translucent", "per-species/translucent",
            "per-species/translucent/detail"} <= modes
    assert {r["setting"] for r in rows} >= {"physical-ff", "paper-ff-0.9", "slices=12", "cone=20deg"}
    for r in rows:
        for k in METRIC_KEYS:
            assert r[k] not in ("", None), (r["mode"], k)
        assert 0 < float(r["rmse"]) and -1 <= float(r["ssim"]) <= 1
    for png in ("demo-cumulus_front_side_by_side.png", "fig7-8_light.png", "convergence_slices.png",
                "calibration_loss.png"):
        assert (tmp_path / png).stat().st_size > 0


def test_validate_cli_rejects_unknown_config(capsys):
    with pytest.raises(SystemExit):
        main(["validate", "--config", "huge"])
