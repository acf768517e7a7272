"""tools/compare_families.py: one study family against another from archived tables, each column's means and the
difference's 95 % interval by Welch's t, checked on samples whose interval is known in closed form."""
import json
import math
import subprocess
import sys

import pytest
from scipy import stats

from paths import TOOLS


def _archive(folder, rows):
    folder.mkdir()
    (folder / "table.json").write_text(json.dumps(rows))
    return folder


def _row(name, family, status="finished", **values):
    return {"name": name, "family": family, "status": status, "gas.u_over_umf": 2.0, **values}


def test_two_families_differences_come_with_welchs_interval(tmp_path):
    # equal sizes and variances: Welch's degrees of freedom are 2n - 2 and the interval d +- t s sqrt(2/n)
    variant = _archive(tmp_path / "a", [_row(f"v{k}", "force", t95=x, mixing=0.9) for k, x in enumerate([5.0, 6.0, 7.0])]
                       + [_row("v9", "force", status="stopped", t95=None)])
    baseline = _archive(tmp_path / "b", [_row(f"b{k}", "base", t95=x) for k, x in enumerate([4.0, 5.0, 6.0])]
                        + [_row("b8", "base", t95=None), _row("b9", "other", t95=99.0)])
    result = subprocess.run([sys.executable, str(TOOLS / "compare_families.py"), "--variant", f"{variant}:force",
                             "--baseline", f"{baseline}:base", "--velocity", "2.0", "--columns", "t95"],
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    entry = json.loads(result.stdout.strip().splitlines()[-1])["columns"]["t95"]
    assert entry["variant"] == {"runs": 3, "mean": 6.0, "sd": 1.0} and entry["baseline"]["runs"] == 3
    half = stats.t.ppf(0.975, 4) * math.sqrt(2.0 / 3.0)
    assert entry["difference"] == pytest.approx(1.0) and entry["interval"] == pytest.approx([1 - half, 1 + half])
    assert entry["left_out"] == [0, 1]  # the stopped run is not counted; the ended one without t95 is said
    assert "t95: 6 ± 1 (3) against 5 ± 1 (3); difference +1" in result.stdout


@pytest.mark.parametrize("variant, message", [("nowhere", "give ARCHIVE:FAMILY"),
                                              ("{tmp}/none:force", "not a study archive")])
def test_bad_sides_are_refused_clearly(tmp_path, variant, message):
    base = _archive(tmp_path / "b", [_row("b0", "base", t95=1.0)])
    result = subprocess.run([sys.executable, str(TOOLS / "compare_families.py"), "--variant",
                             variant.format(tmp=tmp_path), "--baseline", f"{base}:base", "--columns", "t95"],
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 2 and message in result.stderr and "Traceback" not in result.stderr
