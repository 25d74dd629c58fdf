"""validation/calibrate_slicer.py's evaluation of an earlier fit (--fitted) and its refusal of a bad file."""
import json
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from validation import calibrate_slicer as cs  # noqa: E402


def test_fitted_file_is_checked(tmp_path):
    good = tmp_path / "good.json"
    good.write_text(json.dumps({"ms_extinction": 0.2, "diffusion_flux": 0.3}))
    assert cs.read_fitted(good) == {"ms_extinction": 0.2, "diffusion_flux": 0.3}
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"ms_extinction": 0.2, "no_such_parameter": 1.0}))
    with pytest.raises(SystemExit, match=r"bad\.json.*unknown: \['no_such_parameter'\]"):
        cs.read_fitted(bad)
    text = tmp_path / "text.json"
    text.write_text(json.dumps({"ms_extinction": "high"}))
    with pytest.raises(SystemExit, match=r"text\.json.*object of numbers"):
        cs.read_fitted(text)
    broken = tmp_path / "broken.json"
    broken.write_text("{")
    with pytest.raises(SystemExit, match=r"broken\.json: not a readable JSON"):
        cs.read_fitted(broken)


def test_fitted_column_is_named_after_its_file(tmp_path):
    """--fitted evaluates without fitting; its column carries the file's name (held-out storms absent here:
    the held-out table is its header)."""
    fit = tmp_path / "earlier_fit.json"
    fit.write_text(json.dumps({"ms_extinction": 0.2}))
    out = tmp_path / "out"
    assert cs.main(["-o", str(out), "--data", str(tmp_path / "no-data"), "--size", "8x6", "--spp", "2",
                    "--fitted", str(fit), "--held-out-only"]) == 0
    text = (out / "calibration.md").read_text()
    assert "| multiple (defaults) | multiple (earlier_fit) |" in text
    assert "Parameters of an earlier fit" in text and "Fitted on" not in text
