"""The uniform-bed pressure gradient tools/fixed_bed_layers.py and validate_umf.py compare the
simulated bed with (``fvdem.analysis.bed.uniform_bed_pressure_gradient``)."""
import numpy as np
import pytest

from fvdem.analysis.bed import uniform_bed_pressure_gradient, uniform_bed_umf
from fvdem.coupling.bridge import HydrodynamicModel


@pytest.mark.parametrize("drag,length", [("hoelzer-sommerfeld", 5.3e-3), ("gidaspow", 5.3e-3),
                                         ("sanjeevi-padding", 12.8e-3)])
def test_uniform_gradient_at_the_closures_umf_holds_the_bed_weight(drag, length):
    """At the closure's own uniform-bed Umf the gradient is the buoyant bed weight per volume,
    eps_s (rho_p - rho_f) g: the force balance uniform_bed_umf solves, from the other side."""
    diameter = 5.3e-3 if length == 5.3e-3 else 3.2e-3
    model = HydrodynamicModel(drag, "none", "none", diameter, length, 1.2, 1.568e-5)
    rng = np.random.default_rng(1)
    axes = rng.normal(size=(50, 3))
    axes /= np.linalg.norm(axes, axis=1)[:, None]
    voidage, density = 0.45, 1442.0
    umf = uniform_bed_umf(model, voidage, axes, density)
    gradient = uniform_bed_pressure_gradient(model, voidage, umf, axes)
    assert gradient == pytest.approx((1 - voidage) * (density - 1.2) * 9.81, rel=1e-6)
    # and it grows with the velocity and falls with the voidage
    assert uniform_bed_pressure_gradient(model, voidage, 1.1 * umf, axes) > gradient
    assert uniform_bed_pressure_gradient(model, 0.5, umf, axes) < gradient
