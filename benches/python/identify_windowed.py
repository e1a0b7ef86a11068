"""Windowed (weak-form) harmonic balance, method notes section 7, in NumPy.

Windows of 2 forcing periods (2P samples and the closing sample, T_seg = 4 pi) start at every
forcing period of the record. In each window the angle is unwrapped to x_c, and for the test
functions psi = w cos(j tau / k), w sin(j tau / k), j = 0..16 (j = 0: the cosine only), k = 2,
w = sin^4(pi tau / T_seg) (psi and psi' vanish at both ends), integration by parts gives one row

    c_r (-int psi' x_c) + sum_i lambda_i int psi g_i = -int psi'' x_c

with g_i = phi(x) cos t, phi(x) sin t, phi(x) for phi = cos x, sin x (t the absolute time), the
derivatives of psi in closed form and the integrals by the trapezoid rule. No derivative of the
data is taken and no window needs to be periodic. All rows are stacked and solved by
numpy.linalg.lstsq.
"""

import math

import numpy as np

import common

PERIODS_PER_WINDOW = 2
MAX_HARMONIC = 16


def test_functions(samples, step, periods=PERIODS_PER_WINDOW, max_harmonic=MAX_HARMONIC):
    """(psi, psi', psi'') on the window's samples tau = 0..(samples-1) step, one row per function."""
    tau = np.arange(samples) * step
    a = math.pi / (tau[-1])
    s, c = np.sin(a * tau), np.cos(a * tau)
    w = s**4
    dw = 4.0 * a * s**3 * c
    ddw = 4.0 * a**2 * (3.0 * s**2 * c**2 - s**4)
    psi, dpsi, ddpsi = [], [], []
    for j in range(max_harmonic + 1):
        om = j / periods
        co, si = np.cos(om * tau), np.sin(om * tau)
        psi.append(w * co)
        dpsi.append(dw * co - om * w * si)
        ddpsi.append(ddw * co - 2.0 * om * dw * si - om**2 * w * co)
        if j > 0:
            psi.append(w * si)
            dpsi.append(dw * si + om * w * co)
            ddpsi.append(ddw * si + 2.0 * om * dw * co - om**2 * w * si)
    return np.array(psi), np.array(dpsi), np.array(ddpsi)


def identify(t, x, p=common.SAMPLES_PER_PERIOD, periods=PERIODS_PER_WINDOW,
             max_harmonic=MAX_HARMONIC):
    """Coefficients (c_r, n_cos, p_cos, q_cos, n_sin, p_sin, q_sin) and the number of windows."""
    samples = periods * p + 1
    step = 2.0 * math.pi / p
    starts = np.arange(0, x.size - samples + 1, p)
    index = starts[:, None] + np.arange(samples)  # (windows, samples)
    xw = x[index]
    xc = np.unwrap(xw, axis=1)
    tw = t[index]
    cos_t, sin_t = np.cos(tw), np.sin(tw)
    cos_x, sin_x = np.cos(xw), np.sin(xw)
    g = np.stack([cos_x * cos_t, cos_x * sin_t, cos_x,
                  sin_x * cos_t, sin_x * sin_t, sin_x], axis=2)  # (windows, samples, 6)
    weights = np.full(samples, step)
    weights[[0, -1]] *= 0.5
    psi, dpsi, ddpsi = test_functions(samples, step, periods, max_harmonic)
    psi, dpsi, ddpsi = psi * weights, dpsi * weights, ddpsi * weights
    rows = np.concatenate([-(xc @ dpsi.T)[:, :, None],              # (windows, tests, 1)
                           np.einsum("js,wsf->wjf", psi, g)], axis=2)  # (windows, tests, 6)
    rhs = -(xc @ ddpsi.T)
    coefficients, *_ = np.linalg.lstsq(rows.reshape(-1, 7), rhs.reshape(-1), rcond=None)
    return coefficients, starts.size


def bench(t, x, repeats=5):
    """Median seconds of the whole path from the loaded record, and (coefficients, windows)."""
    return common.median_time(lambda: identify(t, x), repeats)


def main():
    t, x = common.load_paper_dataset()
    seconds, (coefficients, windows) = bench(t, x)
    print(f"weak form over {windows} windows of {PERIODS_PER_WINDOW} periods, "
          f"{2 * MAX_HARMONIC + 1} test functions each:")
    print(common.format_errors(coefficients))
    print(f"time (windows + assembly + solve): {seconds * 1e3:.2f} ms (median of 5)")


if __name__ == "__main__":
    main()
