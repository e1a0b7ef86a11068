"""The paper's data set with SciPy: solve_ivp(method="DOP853"), the usual Python way.

x'' + 0.03 x' + (1/0.8333^2) sin x - 1.52 sin(t) cos x = 0 from (x, x') = (0.1, 0), integrated
through 200 forcing periods of transient, then sampled at t_n = n 2 pi / 25 for 30000 samples
(t_eval, dense output of the integrator), rtol 1e-10, atol 1e-11.

Run alone (`python3 simulate.py`) it also checks the integrator against
shared/fixtures/reference_trajectory.csv (8 periods, rtol 1e-12) and times the data set once.
"""

import math

import numpy as np
from scipy.integrate import solve_ivp

import common

TRANSIENT_PERIODS = 200
SAMPLES = 30000
INITIAL_STATE = (0.1, 0.0)


def rhs(t, y):
    """(x', x'') of the pendulum at state y = (x, x')."""
    x, v = y
    return [v, -common.C * v - math.sin(x) / common.R**2 + common.F * math.sin(t) * math.cos(x)]


def integrate(t_eval, rtol, atol):
    """theta (continuous) and omega at the times t_eval, from t = 0."""
    sol = solve_ivp(
        rhs, (0.0, t_eval[-1]), INITIAL_STATE, method="DOP853", t_eval=t_eval, rtol=rtol, atol=atol
    )
    if not sol.success:
        raise RuntimeError(f"solve_ivp failed: {sol.message}")
    return sol.y[0], sol.y[1]


def sample_times():
    """t_n = n 2 pi / P for the SAMPLES samples after the transient."""
    first = TRANSIENT_PERIODS * common.SAMPLES_PER_PERIOD
    return np.arange(first, first + SAMPLES) * common.STEP


def simulate():
    """The paper's data set: (t, wrapped theta)."""
    t = sample_times()
    theta, _ = integrate(t, rtol=1e-10, atol=1e-11)
    return t, common.wrap(theta)


def check_reference():
    """Largest |difference| of theta and omega against reference_trajectory.csv (rtol 1e-12)."""
    ref = common.load_csv(common.REFERENCE_TRAJECTORY)
    theta, omega = integrate(ref["t"], rtol=1e-12, atol=1e-13)
    return np.max(np.abs(theta - ref["theta"])), np.max(np.abs(omega - ref["omega"]))


def bench(repeats=1, warmup=False):
    """Median seconds of `simulate()`; one run takes seconds, so no warm-up by default."""
    seconds, (t, x) = common.median_time(simulate, repeats, warmup=warmup)
    return seconds, (t, x)


def main():
    d_theta, d_omega = check_reference()
    print(f"reference_trajectory.csv (8 periods, rtol 1e-12): max |d theta| = {d_theta:.2e}, "
          f"max |d omega| = {d_omega:.2e}")
    seconds, (t, x) = bench()
    print(f"paper data set: {x.size} samples, t = {t[0]:.4f} .. {t[-1]:.4f}, "
          f"theta in [{x.min():.4f}, {x.max():.4f}]")
    print(f"solve_ivp DOP853 rtol 1e-10: {seconds:.3f} s (one run)")


if __name__ == "__main__":
    main()
