"""The paper's identification (harmonic balance over close returns, eqs. 10-17) in NumPy.

For every segment of close_returns.py (start n, period k, L = kP samples): unwrap the angle
(closing sample included) to x_c; winding number m = round((x_c[L] - x_c[0]) / 2 pi), rotation
rate w = m / k; x_var = x_c - w tau, tau = 0, h, ..., (L-1) h. Fourier coefficients of a segment by
np.fft.rfft (S_j = sum s_n e^{-2 pi i j n / L}; a_j = 2 Re S_j / L, b_j = -2 Im S_j / L), for x_var
(u, v) and for phi(x), phi(x) cos t, phi(x) sin t with the harmonic basis phi = cos x, sin x and
the forcing at the absolute time t of each sample. The rows of eq. 15 for harmonics j = 0..M
(M = 12 of the orbit's own fundamental 1/k), unknowns (c_r, n_cos, p_cos, q_cos, n_sin, p_sin,
q_sin):

    row 0:      c_r w            + sum_i [n_i e_i0/2 + p_i g_i0/2 + q_i c_i0/2] = 0
    row cos j:  c_r (j/k) v_j    + sum_i [n_i e_ij   + p_i g_ij   + q_i c_ij  ] = (j/k)^2 u_j
    row sin j: -c_r (j/k) u_j    + sum_i [n_i f_ij   + p_i h_ij   + q_i d_ij  ] = (j/k)^2 v_j

stacked over all segments (eq. 16) and solved by numpy.linalg.lstsq (SVD; never A^T A).
"""

import math

import numpy as np

import close_returns
import common

HARMONICS = 12


def orbit_rows(t, x, start, k, p=common.SAMPLES_PER_PERIOD, harmonics=HARMONICS):
    """(A_k, beta_k) of eq. 15 for the period-k segment at `start`: 2 M + 1 rows, 7 columns."""
    length = k * p
    xc = np.unwrap(x[start : start + length + 1])
    m = round((xc[-1] - xc[0]) / (2.0 * math.pi))
    w = m / k
    tau = np.arange(length) * common.STEP
    xs = x[start : start + length]
    ts = t[start : start + length]
    cos_t, sin_t = np.cos(ts), np.sin(ts)
    cos_x, sin_x = np.cos(xs), np.sin(xs)
    # Rows: x_var, then per basis function phi cos t (e, f), phi sin t (g, h), phi (c, d).
    signals = np.stack([xc[:-1] - w * tau,
                        cos_x * cos_t, cos_x * sin_t, cos_x,
                        sin_x * cos_t, sin_x * sin_t, sin_x])
    spectrum = np.fft.rfft(signals, axis=1)[:, : harmonics + 1]
    a = 2.0 * spectrum.real / length
    b = -2.0 * spectrum.imag / length
    u, v = a[0], b[0]
    jk = np.arange(harmonics + 1) / k
    rows = np.empty((2 * harmonics + 1, 7))
    rhs = np.empty(2 * harmonics + 1)
    rows[0, 0] = w
    rows[0, 1:] = a[1:, 0] / 2.0
    rhs[0] = 0.0
    rows[1::2, 0] = jk[1:] * v[1:]
    rows[1::2, 1:] = a[1:, 1:].T
    rhs[1::2] = jk[1:] ** 2 * u[1:]
    rows[2::2, 0] = -jk[1:] * u[1:]
    rows[2::2, 1:] = b[1:, 1:].T
    rhs[2::2] = jk[1:] ** 2 * v[1:]
    return rows, rhs


def identify(t, x, harmonics=HARMONICS):
    """Close returns, rows of every segment, least squares: (coefficients, number of segments)."""
    segments = close_returns.close_returns(x)
    blocks = [orbit_rows(t, x, int(start), int(k), harmonics=harmonics) for start, k, _ in segments]
    a = np.concatenate([rows for rows, _ in blocks])
    beta = np.concatenate([rhs for _, rhs in blocks])
    coefficients, *_ = np.linalg.lstsq(a, beta, rcond=None)
    return coefficients, len(segments)


def bench(t, x, repeats=5):
    """Median seconds of the whole path from the loaded record, and (coefficients, segments)."""
    return common.median_time(lambda: identify(t, x), repeats)


def main():
    t, x = common.load_paper_dataset()
    seconds, (coefficients, segments) = bench(t, x)
    print(f"harmonic balance over {segments} close-return segments, K = 1, M = {HARMONICS}:")
    print(common.format_errors(coefficients))
    print(f"time (close returns + assembly + solve): {seconds * 1e3:.2f} ms (median of 5)")


if __name__ == "__main__":
    main()
