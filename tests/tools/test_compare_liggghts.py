"""tools/compare_liggghts.py writes the bed and the contact model LIGGGHTS reads (issue 16, point 4)."""
import re
import sys

import numpy as np
import pytest

from paths import ROOT, TOOLS

sys.path.insert(0, str(TOOLS))

import compare_liggghts  # noqa: E402


def test_the_data_file_and_input_hold_fvdems_bed_and_contact_model(tmp_path):
    import fvdem
    from fvdem.dem.contact_law import K_N, ZETA_N, normal_damping
    from fvdem.model import build_dem, build_particles
    case = fvdem.load_case(ROOT / "cases" / "bed_ar1.toml", {"particles.count": 30,
                                                             "particles.insertion.upper": [0.15, 0.15, 0.1]})
    dem = build_dem(case, build_particles(case))
    p = dem.particles
    p.velocity[:] = np.random.default_rng(0).normal(0, 0.1, p.velocity.shape)
    compare_liggghts.write_data(tmp_path / "bed.data", p, case.domain.lower, case.domain.upper)
    text = (tmp_path / "bed.data").read_text()
    assert "30 atoms" in text and "0 0.15 xlo xhi" in text and "0 1.05 zlo zhi" in text
    atoms = text.split("Atoms\n\n")[1].split("\n\nVelocities")[0].splitlines()
    first = [float(v) for v in atoms[0].split()]
    assert first[2] == pytest.approx(2 * p.radius[0], rel=1e-11) and first[3] == pytest.approx(1442.0, rel=1e-11)
    np.testing.assert_allclose(first[4:7], p.position[0], rtol=1e-11)
    velocities = text.split("Velocities\n\n")[1].splitlines()
    np.testing.assert_allclose([float(v) for v in velocities[0].split()[1:4]], p.velocity[0], rtol=1e-11)
    script = compare_liggghts.input_script(case, dem, "bed.data", 100, 10)
    value = {name: float(re.search(rf"property/global {name} peratomtypepair 1 (\S+)", script).group(1))
             for name in ("kn", "kt", "gamman", "gammat", "coefficientFriction", "coefficientRollingFriction")}
    m_eff = 0.5 * p.mass[0]
    assert value["kn"] == 2.0e4 and value["kt"] == pytest.approx(2.0e4 * case.contact.tangential_stiffness_ratio)
    # LIGGGHTS's dashpot without absolute damping is gamma_n m_eff v_n: fvdem's calibrated eta_n
    assert value["gamman"] * m_eff == pytest.approx(normal_damping(dem.params[ZETA_N], m_eff, dem.params[K_N]), rel=1e-10)
    assert value["coefficientFriction"] == 0.46 and value["coefficientRollingFriction"] == 0.46
    assert script.count("wall/gran") == 6 and "timestep 1e-05" in script and "run 100" in script
    assert f"neighbor {dem.skin:.9g} bin" in script
