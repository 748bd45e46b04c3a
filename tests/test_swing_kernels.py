"""Issue 30, item 1 (in progress): the swing estimator compiled gives the NumPy reference's numbers bit for bit."""

import numpy as np
import pytest

from app.control.antisway import SwingEkf
from app.control.antisway_kernels import ekf_block


@pytest.mark.parametrize("measurement", ["angles", "payload"])
def test_the_compiled_ekf_step_equals_the_reference_bit_for_bit(measurement):
    """3,000 seeded steps (random tool accelerations, a paying-out wire, noisy measurements): the estimate,
    its covariance and the NIS equal SwingEkf's to the last bit at every step."""
    rng = np.random.default_rng(7)
    ekf = SwingEkf(c=0.1, measurement=measurement, sigma_pos=0.005)
    xh, P = ekf.x.copy(), ekf.P.copy()
    p = (ekf.c, ekf.g, ekf.sigma_accel, ekf.sigma_model, measurement == "payload", ekf.sigma_angle, ekf.sigma_pos)
    L, dt = 3.0, 0.005
    for _ in range(3000):
        a, Ld = rng.normal(0.0, 0.5, 3), rng.normal(0.0, 0.05)
        if measurement == "angles":
            z = rng.normal(0.0, 0.05, 2)
        else:
            z = L * np.array([0.02, 0.03, 1.0]) + rng.normal(0.0, 0.01, 3)
        ekf.predict(dt, a, L, Ld)
        ekf.update(z, L + Ld * dt)
        _, (y, nis) = ekf_block((xh, P), (a, L, Ld, z, L + Ld * dt), p, dt)
        L += Ld * dt
        np.testing.assert_array_equal(xh, ekf.x)
        np.testing.assert_array_equal(P, ekf.P)
        np.testing.assert_array_equal(y, ekf.innovation)
        assert nis == ekf.nis
