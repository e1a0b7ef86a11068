//! The basis functions `φ_i(x)` of paper eqs. 4-5.

use std::f64::consts::{PI, TAU};
use std::fmt;

use circle_signal::wrap;
use serde::{Deserialize, Serialize};

use crate::error::BasisError;

pub use circle_signal::Domain;

/// A finite set of functions `φ_1 .. φ_N` of the displacement, used to expand the unknown
/// autonomous and parametric parts of the equation of motion (paper eqs. 4-5).
///
/// Object safe, so a program can choose a basis at run time (`Box<dyn Basis>`). Bases on the circle
/// ([`Domain::Circle`]) are 2π-periodic: `φ(x + 2π) = φ(x)`.
///
/// `eval` and `eval_deriv` write into a caller's buffer so that evaluation over a long record
/// allocates nothing; NaN or infinite `x` gives NaN in (at least one entry of) the output.
pub trait Basis: fmt::Debug + Send + Sync {
    /// Number of functions `N`.
    fn len(&self) -> usize;

    /// Whether the basis has no function (never true for the bases of this crate).
    fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Name of function `i` (`None` if `i >= len()`), e.g. `sin(2x)`, `hat3`, `x^2`.
    fn name(&self, i: usize) -> Option<String>;

    /// Names of all functions, in order.
    fn names(&self) -> Vec<String> {
        (0..self.len()).filter_map(|i| self.name(i)).collect()
    }

    /// Whether the basis lives on the circle or the line.
    fn domain(&self) -> Domain;

    /// Writes `φ_i(x)` for every `i` into `out[..len()]`.
    ///
    /// # Panics
    /// If `out.len() < self.len()`.
    fn eval(&self, x: f64, out: &mut [f64]);

    /// Writes the derivatives `dφ_i/dx (x)` into `out[..len()]` (for the hat basis, the derivative
    /// from the right at a node).
    ///
    /// # Panics
    /// If `out.len() < self.len()`.
    fn eval_deriv(&self, x: f64, out: &mut [f64]);

    /// Writes an antiderivative `Φ_i` of every function into `out[..len()]` (`dΦ_i/dx = φ_i`), at
    /// any real `x`, which is **not** wrapped: on the circle a function with a nonzero mean has an
    /// antiderivative that grows with the unwrapped angle, `Φ_i(x + 2π) = Φ_i(x) + ∫_{−π}^{π} φ_i`.
    /// The constant of integration is the basis' choice (what uses `Φ` takes its differences).
    ///
    /// Terms linear in the velocity need it: `φ(x) x'` is the time derivative of `Φ(x)`, so the
    /// weak form integrates it by parts exactly, `∫ ψ φ(x) x' = −∫ ψ' Φ(x)`.
    ///
    /// The provided implementation integrates [`eval`](Basis::eval) by 8-point Gauss–Legendre
    /// quadrature on panels of at most `2π/32` (on the circle, from `−π` to the wrapped `x`, plus
    /// the whole turns) or `1/8` (on the line, from 0, at most 4096 panels); it allocates, and is
    /// exact to rounding only for functions smooth on each panel. The bases of this crate override
    /// it with closed forms.
    ///
    /// # Panics
    /// If `out.len() < self.len()`.
    fn eval_antiderivative(&self, x: f64, out: &mut [f64]) {
        quadrature_antiderivative(self, x, out)
    }
}

impl<B: Basis + ?Sized> Basis for &B {
    fn len(&self) -> usize {
        (**self).len()
    }
    fn name(&self, i: usize) -> Option<String> {
        (**self).name(i)
    }
    fn domain(&self) -> Domain {
        (**self).domain()
    }
    fn eval(&self, x: f64, out: &mut [f64]) {
        (**self).eval(x, out)
    }
    fn eval_deriv(&self, x: f64, out: &mut [f64]) {
        (**self).eval_deriv(x, out)
    }
    fn eval_antiderivative(&self, x: f64, out: &mut [f64]) {
        (**self).eval_antiderivative(x, out)
    }
}

impl<B: Basis + ?Sized> Basis for Box<B> {
    fn len(&self) -> usize {
        (**self).len()
    }
    fn name(&self, i: usize) -> Option<String> {
        (**self).name(i)
    }
    fn domain(&self) -> Domain {
        (**self).domain()
    }
    fn eval(&self, x: f64, out: &mut [f64]) {
        (**self).eval(x, out)
    }
    fn eval_deriv(&self, x: f64, out: &mut [f64]) {
        (**self).eval_deriv(x, out)
    }
    fn eval_antiderivative(&self, x: f64, out: &mut [f64]) {
        (**self).eval_antiderivative(x, out)
    }
}

fn check_len(out: &[f64], n: usize) {
    assert!(
        out.len() >= n,
        "output buffer of {} for a basis of {n} functions",
        out.len()
    );
}

/// Nodes and weights of 8-point Gauss–Legendre quadrature on `[−1, 1]`.
const GAUSS_8: [(f64, f64); 8] = [
    (-0.960_289_856_497_536_3, 0.101_228_536_290_376_26),
    (-0.796_666_477_413_626_7, 0.222_381_034_453_374_47),
    (-0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (-0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (0.796_666_477_413_626_7, 0.222_381_034_453_374_47),
    (0.960_289_856_497_536_3, 0.101_228_536_290_376_26),
];

/// `∫_a^b φ_i` for every `i` into `out` (added to what is there), by [`GAUSS_8`] on `panels`
/// equal panels.
fn add_integral<B: Basis + ?Sized>(
    basis: &B,
    a: f64,
    b: f64,
    panels: usize,
    phi: &mut [f64],
    out: &mut [f64],
) {
    let n = basis.len();
    let width = (b - a) / panels as f64;
    for p in 0..panels {
        let mid = a + (p as f64 + 0.5) * width;
        for &(node, weight) in &GAUSS_8 {
            basis.eval(mid + 0.5 * width * node, phi);
            for (o, &v) in out[..n].iter_mut().zip(phi.iter()) {
                *o += 0.5 * width * weight * v;
            }
        }
    }
}

/// The provided [`Basis::eval_antiderivative`]: quadrature of [`Basis::eval`].
fn quadrature_antiderivative<B: Basis + ?Sized>(basis: &B, x: f64, out: &mut [f64]) {
    let n = basis.len();
    check_len(out, n);
    out[..n].fill(0.0);
    if !x.is_finite() {
        out[..n].fill(f64::NAN);
        return;
    }
    let mut phi = vec![0.0; n];
    match basis.domain() {
        Domain::Circle => {
            let panel = TAU / 32.0;
            let base = wrap(x);
            let turns = ((x - base) / TAU).round();
            if turns != 0.0 {
                let mut turn = vec![0.0; n];
                add_integral(basis, -PI, PI, 32, &mut phi, &mut turn);
                for (o, t) in out[..n].iter_mut().zip(&turn) {
                    *o = turns * t;
                }
            }
            let panels = (((base + PI) / panel).ceil() as usize).max(1);
            add_integral(basis, -PI, base, panels, &mut phi, out);
        }
        Domain::Line => {
            let panels = ((x.abs() * 8.0).ceil() as usize).clamp(1, 4096);
            add_integral(basis, 0.0, x, panels, &mut phi, out);
        }
    }
}

// ---------------------------------------------------------------------------------------------

/// Harmonic basis of order `K` on the circle: `cos(x), sin(x), cos(2x), sin(2x), .., cos(Kx), sin(Kx)`
/// (paper section 4.2.1, eq. 20), named `cos(x)`, `sin(x)`, `cos(2x)`, ...
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(try_from = "HarmonicRaw", into = "HarmonicRaw")]
pub struct Harmonic {
    order: usize,
}

#[derive(Serialize, Deserialize)]
struct HarmonicRaw {
    order: usize,
}

impl TryFrom<HarmonicRaw> for Harmonic {
    type Error = BasisError;
    fn try_from(raw: HarmonicRaw) -> Result<Self, BasisError> {
        Self::new(raw.order)
    }
}

impl From<Harmonic> for HarmonicRaw {
    fn from(h: Harmonic) -> Self {
        Self { order: h.order }
    }
}

impl Harmonic {
    /// The harmonic basis of order `K >= 1` (`2K` functions).
    pub fn new(order: usize) -> Result<Self, BasisError> {
        if order < 1 {
            return Err(BasisError::TooSmall {
                name: "harmonic order K",
                value: order,
                min: 1,
            });
        }
        at_most("harmonic order K", order, crate::MAX_FUNCTIONS / 2)?;
        Ok(Self { order })
    }

    /// The order `K`.
    pub fn order(&self) -> usize {
        self.order
    }
}

impl Basis for Harmonic {
    fn len(&self) -> usize {
        2 * self.order
    }

    fn name(&self, i: usize) -> Option<String> {
        if i >= self.len() {
            return None;
        }
        let k = i / 2 + 1;
        let f = if i.is_multiple_of(2) { "cos" } else { "sin" };
        Some(if k == 1 {
            format!("{f}(x)")
        } else {
            format!("{f}({k}x)")
        })
    }

    fn domain(&self) -> Domain {
        Domain::Circle
    }

    fn eval(&self, x: f64, out: &mut [f64]) {
        check_len(out, self.len());
        let (s1, c1) = x.sin_cos();
        let (mut c, mut s) = (c1, s1);
        for k in 0..self.order {
            out[2 * k] = c;
            out[2 * k + 1] = s;
            // cos((k+1)x), sin((k+1)x) by the angle-addition formulas.
            (c, s) = (c * c1 - s * s1, s * c1 + c * s1);
        }
    }

    fn eval_deriv(&self, x: f64, out: &mut [f64]) {
        check_len(out, self.len());
        let (s1, c1) = x.sin_cos();
        let (mut c, mut s) = (c1, s1);
        for k in 0..self.order {
            let kf = (k + 1) as f64;
            out[2 * k] = -kf * s;
            out[2 * k + 1] = kf * c;
            (c, s) = (c * c1 - s * s1, s * c1 + c * s1);
        }
    }

    /// `sin(kx)/k` for `cos(kx)` and `−cos(kx)/k` for `sin(kx)`: periodic, since the functions
    /// have mean zero.
    fn eval_antiderivative(&self, x: f64, out: &mut [f64]) {
        check_len(out, self.len());
        let (s1, c1) = x.sin_cos();
        let (mut c, mut s) = (c1, s1);
        for k in 0..self.order {
            let kf = (k + 1) as f64;
            out[2 * k] = s / kf;
            out[2 * k + 1] = -c / kf;
            (c, s) = (c * c1 - s * s1, s * c1 + c * s1);
        }
    }
}

// ---------------------------------------------------------------------------------------------

/// `value` of the size parameter `name`, refused beyond `max`.
fn at_most(name: &'static str, value: usize, max: usize) -> Result<(), BasisError> {
    match value > max {
        true => Err(BasisError::TooLarge { name, value, max }),
        false => Ok(()),
    }
}

/// Periodic linear-interpolation ("hat") basis on the circle (paper section 4.2.2).
///
/// `N` nodes evenly over `[−π, π)`, node `i` at `x_i = −π + 2π i / N`, spacing `d = 2π / N`.
/// `hat_i` is 1 at node `i`, 0 at every other node and linear in between; node `N − 1` and node
/// `0` are neighbours across `±π`, so the hats sum to 1 everywhere. `x` is wrapped into `[−π, π)`
/// before evaluation. Names `hat0` .. `hat{N-1}`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(try_from = "HatRaw", into = "HatRaw")]
pub struct Hat {
    nodes: usize,
}

#[derive(Serialize, Deserialize)]
struct HatRaw {
    nodes: usize,
}

impl TryFrom<HatRaw> for Hat {
    type Error = BasisError;
    fn try_from(raw: HatRaw) -> Result<Self, BasisError> {
        Self::new(raw.nodes)
    }
}

impl From<Hat> for HatRaw {
    fn from(h: Hat) -> Self {
        Self { nodes: h.nodes }
    }
}

impl Hat {
    /// The hat basis with `N >= 3` nodes.
    pub fn new(nodes: usize) -> Result<Self, BasisError> {
        if nodes < 3 {
            return Err(BasisError::TooSmall {
                name: "number of hat nodes N",
                value: nodes,
                min: 3,
            });
        }
        at_most("number of hat nodes N", nodes, crate::MAX_FUNCTIONS)?;
        Ok(Self { nodes })
    }

    /// The number of nodes `N`.
    pub fn nodes(&self) -> usize {
        self.nodes
    }

    /// Position of node `i`, `−π + 2π i / N`.
    pub fn node(&self, i: usize) -> f64 {
        -PI + TAU * i as f64 / self.nodes as f64
    }

    /// The coefficients `c` of the L2 projection of a function `f` onto the hats: the curve
    /// `Σ_i c_i hat_i(x)` closest to `f` in the mean square over the circle (for instance the best
    /// that a hat model can do on a true curve, to which an identified curve is compared).
    ///
    /// They solve the Gram system `M c = b` with `M_ij = ∫ hat_i hat_j` and `b_i = ∫ f hat_i` over
    /// `[−π, π)`, both integrals by the midpoint rule on `points` evenly spaced points
    /// `x_s = −π + 2π (s + ½) / points`. `M` is symmetric positive definite once every interval
    /// between nodes holds two points, so `points` must be at least `2 N`; it is solved by Gaussian
    /// elimination without pivoting. A function already in the span of the hats is returned
    /// exactly (to rounding), and the residual `f − Σ c_i hat_i` is orthogonal to every hat in
    /// the quadrature's inner product.
    ///
    /// # Errors
    /// [`BasisError::TooSmall`] if `points < 2 N`; [`BasisError::NonFinite`] if `f` is NaN or
    /// infinite at a quadrature point (`index` is the point).
    ///
    /// # Example
    ///
    /// ```
    /// use hb_basis::{Basis, Hat};
    ///
    /// let hat = Hat::new(8)?;
    /// // sin x is not piecewise linear: its projection is a hat curve near it...
    /// let c = hat.project(4096, f64::sin)?;
    /// let mut phi = vec![0.0; hat.len()];
    /// hat.eval(1.0, &mut phi);
    /// let fit: f64 = phi.iter().zip(&c).map(|(p, c)| p * c).sum();
    /// assert!((fit - 1f64.sin()).abs() < 0.05);
    /// // ...while a hat curve projects onto itself.
    /// let c = hat.project(4096, |x| {
    ///     hat.eval(x, &mut phi);
    ///     2.0 * phi[3] - phi[5]
    /// })?;
    /// assert!((c[3] - 2.0).abs() < 1e-12 && (c[5] + 1.0).abs() < 1e-12 && c[0].abs() < 1e-12);
    /// # Ok::<(), hb_basis::BasisError>(())
    /// ```
    pub fn project(&self, points: usize, mut f: impl FnMut(f64) -> f64) -> Result<Vec<f64>, BasisError> {
        let n = self.nodes;
        if points < 2 * n {
            return Err(BasisError::TooSmall {
                name: "quadrature points of a hat projection",
                value: points,
                min: 2 * n,
            });
        }
        let mut gram = vec![0.0; n * n];
        let mut b = vec![0.0; n];
        for s in 0..points {
            let x = -PI + TAU * (s as f64 + 0.5) / points as f64;
            let fx = f(x);
            if !fx.is_finite() {
                return Err(BasisError::NonFinite { index: s, value: fx });
            }
            // Only two hats are non-zero at x: hat_i = 1 − frac and hat_{i+1} = frac.
            let (i, frac) = self.locate(x);
            let pair = [(i, 1.0 - frac), ((i + 1) % n, frac)];
            for &(r, phi_r) in &pair {
                b[r] += phi_r * fx;
                for &(c, phi_c) in &pair {
                    gram[r * n + c] += phi_r * phi_c;
                }
            }
        }
        // Forward elimination; the pivots of a symmetric positive definite matrix are positive.
        for c in 0..n {
            for r in c + 1..n {
                let factor = gram[r * n + c] / gram[c * n + c];
                for k in c..n {
                    gram[r * n + k] -= factor * gram[c * n + k];
                }
                b[r] -= factor * b[c];
            }
        }
        let mut coefficients = vec![0.0; n];
        for r in (0..n).rev() {
            let s: f64 = (r + 1..n).map(|k| gram[r * n + k] * coefficients[k]).sum();
            coefficients[r] = (b[r] - s) / gram[r * n + r];
        }
        Ok(coefficients)
    }

    /// The interval containing `x`: the left node `i`, and the fraction `s ∈ [0, 1]` of the way
    /// to node `i + 1 (mod N)`.
    #[inline]
    fn locate(&self, x: f64) -> (usize, f64) {
        let n = self.nodes;
        let pos = (wrap(x) + PI) * (n as f64 / TAU);
        // NaN casts to 0; the fraction stays NaN and poisons the output as documented.
        let i = (pos.floor() as usize).min(n - 1);
        let frac = pos - i as f64;
        (i, if frac.is_nan() { frac } else { frac.clamp(0.0, 1.0) })
    }
}

impl Basis for Hat {
    fn len(&self) -> usize {
        self.nodes
    }

    fn name(&self, i: usize) -> Option<String> {
        (i < self.nodes).then(|| format!("hat{i}"))
    }

    fn domain(&self) -> Domain {
        Domain::Circle
    }

    fn eval(&self, x: f64, out: &mut [f64]) {
        check_len(out, self.nodes);
        let (i, frac) = self.locate(x);
        out[..self.nodes].fill(0.0);
        out[i] = 1.0 - frac;
        out[(i + 1) % self.nodes] = frac;
    }

    fn eval_deriv(&self, x: f64, out: &mut [f64]) {
        check_len(out, self.nodes);
        let (i, frac) = self.locate(x);
        let slope = self.nodes as f64 / TAU;
        out[..self.nodes].fill(0.0);
        if frac.is_nan() {
            out[i] = f64::NAN;
            return;
        }
        out[i] = -slope;
        out[(i + 1) % self.nodes] = slope;
    }

    /// `∫_{−π}^{x} hat_i` for `x` in `[−π, π)`, plus `2π/N` (the integral of every hat over a
    /// turn) for each whole turn of `x` from there.
    fn eval_antiderivative(&self, x: f64, out: &mut [f64]) {
        let n = self.nodes;
        check_len(out, n);
        if !x.is_finite() {
            out[..n].fill(f64::NAN);
            return;
        }
        let d = TAU / n as f64;
        let base = wrap(x);
        let turns = ((x - base) / TAU).round();
        let (j, s) = self.locate(base);
        for (i, o) in out[..n].iter_mut().enumerate() {
            // Whole intervals m < j: hat_i falls over interval i and rises over interval i − 1
            // (interval N − 1 for hat0, which lies after every j).
            let mut v = 0.0;
            if i < j {
                v += 0.5 * d;
            }
            if i >= 1 && i - 1 < j {
                v += 0.5 * d;
            }
            // The part of interval j up to the fraction s.
            if j == i {
                v += d * (s - 0.5 * s * s);
            }
            if (j + 1) % n == i {
                v += 0.5 * d * s * s;
            }
            *o = turns * d + v;
        }
    }
}

// ---------------------------------------------------------------------------------------------

/// Monomials `x, x², .., x^D` on the line, named `x`, `x^2`, ..., `x^D`, for oscillators whose
/// displacement is not an angle (e.g. Duffing).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(try_from = "PolynomialRaw", into = "PolynomialRaw")]
pub struct Polynomial {
    degree: usize,
}

#[derive(Serialize, Deserialize)]
struct PolynomialRaw {
    degree: usize,
}

impl TryFrom<PolynomialRaw> for Polynomial {
    type Error = BasisError;
    fn try_from(raw: PolynomialRaw) -> Result<Self, BasisError> {
        Self::new(raw.degree)
    }
}

impl From<Polynomial> for PolynomialRaw {
    fn from(p: Polynomial) -> Self {
        Self { degree: p.degree }
    }
}

impl Polynomial {
    /// Monomials up to degree `D >= 1`.
    pub fn new(degree: usize) -> Result<Self, BasisError> {
        if degree < 1 {
            return Err(BasisError::TooSmall {
                name: "polynomial degree",
                value: degree,
                min: 1,
            });
        }
        at_most("polynomial degree", degree, crate::MAX_FUNCTIONS)?;
        Ok(Self { degree })
    }

    /// The degree `D`.
    pub fn degree(&self) -> usize {
        self.degree
    }
}

impl Basis for Polynomial {
    fn len(&self) -> usize {
        self.degree
    }

    fn name(&self, i: usize) -> Option<String> {
        (i < self.degree).then(|| {
            if i == 0 {
                "x".to_owned()
            } else {
                format!("x^{}", i + 1)
            }
        })
    }

    fn domain(&self) -> Domain {
        Domain::Line
    }

    fn eval(&self, x: f64, out: &mut [f64]) {
        check_len(out, self.degree);
        let mut p = x;
        for o in &mut out[..self.degree] {
            *o = p;
            p *= x;
        }
    }

    fn eval_deriv(&self, x: f64, out: &mut [f64]) {
        check_len(out, self.degree);
        let mut p = 1.0;
        for (i, o) in out[..self.degree].iter_mut().enumerate() {
            *o = (i + 1) as f64 * p;
            p *= x;
        }
    }

    /// `x^(n+1) / (n+1)` for `x^n`.
    fn eval_antiderivative(&self, x: f64, out: &mut [f64]) {
        check_len(out, self.degree);
        let mut p = x * x;
        for (i, o) in out[..self.degree].iter_mut().enumerate() {
            *o = p / (i + 2) as f64;
            p *= x;
        }
    }
}

// ---------------------------------------------------------------------------------------------

/// One of this crate's bases, chosen at run time and serialisable (so an identified model can be
/// saved with the basis it was built on). It implements [`Basis`] by delegation.
///
/// Serialised externally tagged: `{"harmonic":{"order":1}}`, `{"hat":{"nodes":8}}`,
/// `{"polynomial":{"degree":3}}`; sizes are validated again when read.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BasisKind {
    /// [`Harmonic`].
    Harmonic(Harmonic),
    /// [`Hat`].
    Hat(Hat),
    /// [`Polynomial`].
    Polynomial(Polynomial),
}

impl From<Harmonic> for BasisKind {
    fn from(b: Harmonic) -> Self {
        Self::Harmonic(b)
    }
}

impl From<Hat> for BasisKind {
    fn from(b: Hat) -> Self {
        Self::Hat(b)
    }
}

impl From<Polynomial> for BasisKind {
    fn from(b: Polynomial) -> Self {
        Self::Polynomial(b)
    }
}

impl BasisKind {
    /// The basis of the unknown functions when none is chosen: `harmonic:1` on the circle (the
    /// pendulum's sin and cos), `poly:3` on the line (Duffing's cubic).
    ///
    /// ```
    /// use hb_basis::{BasisKind, Domain};
    ///
    /// assert_eq!(BasisKind::default_for(Domain::Circle).spec(), "harmonic:1");
    /// assert_eq!(BasisKind::default_for(Domain::Line).spec(), "poly:3");
    /// ```
    pub fn default_for(domain: Domain) -> Self {
        match domain {
            Domain::Circle => Self::Harmonic(Harmonic { order: 1 }),
            Domain::Line => Self::Polynomial(Polynomial { degree: 3 }),
        }
    }

    fn inner(&self) -> &dyn Basis {
        match self {
            Self::Harmonic(b) => b,
            Self::Hat(b) => b,
            Self::Polynomial(b) => b,
        }
    }
}

impl BasisKind {
    /// The basis as the command line and saved requests name it: `harmonic:K`, `hat:N` or
    /// `poly:D` (read back by [`str::parse`]).
    pub fn spec(&self) -> String {
        match self {
            Self::Harmonic(b) => format!("harmonic:{}", b.order),
            Self::Hat(b) => format!("hat:{}", b.nodes),
            Self::Polynomial(b) => format!("poly:{}", b.degree),
        }
    }
}

/// Reads [`BasisKind::spec`]: `harmonic:K` (cos kx, sin kx for k = 1..K), `hat:N` (N periodic
/// hats) or `poly:D` (x .. x^D), the size checked by the basis's constructor.
///
/// ```
/// use hb_basis::BasisKind;
///
/// let basis: BasisKind = "hat:8".parse()?;
/// assert_eq!(basis.spec(), "hat:8");
/// assert!("hat:2".parse::<BasisKind>().is_err());
/// assert!("cheb:3".parse::<BasisKind>().is_err());
/// # Ok::<(), hb_basis::BasisError>(())
/// ```
impl std::str::FromStr for BasisKind {
    type Err = BasisError;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let bad = |reason: String| BasisError::BadSpec {
            text: text.to_owned(),
            reason,
        };
        let (kind, n) = text
            .split_once(':')
            .ok_or_else(|| bad("expected harmonic:K, hat:N or poly:D".to_owned()))?;
        let n: usize = n
            .trim()
            .parse()
            .map_err(|_| bad(format!("'{}' is not a whole number", n.trim())))?;
        let checked = |e: BasisError| bad(e.to_string());
        Ok(match kind.trim() {
            "harmonic" => Self::from(Harmonic::new(n).map_err(checked)?),
            "hat" => Self::from(Hat::new(n).map_err(checked)?),
            "poly" => Self::from(Polynomial::new(n).map_err(checked)?),
            other => return Err(bad(format!("unknown basis '{other}' (harmonic, hat or poly)"))),
        })
    }
}

impl fmt::Display for BasisKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Harmonic(b) => write!(f, "harmonic (K = {})", b.order),
            Self::Hat(b) => write!(f, "hat (N = {})", b.nodes),
            Self::Polynomial(b) => write!(f, "polynomial (degree {})", b.degree),
        }
    }
}

impl Basis for BasisKind {
    fn len(&self) -> usize {
        self.inner().len()
    }
    fn name(&self, i: usize) -> Option<String> {
        self.inner().name(i)
    }
    fn domain(&self) -> Domain {
        self.inner().domain()
    }
    fn eval(&self, x: f64, out: &mut [f64]) {
        self.inner().eval(x, out)
    }
    fn eval_deriv(&self, x: f64, out: &mut [f64]) {
        self.inner().eval_deriv(x, out)
    }
    fn eval_antiderivative(&self, x: f64, out: &mut [f64]) {
        self.inner().eval_antiderivative(x, out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names() {
        assert_eq!(
            Harmonic::new(2).unwrap().names(),
            ["cos(x)", "sin(x)", "cos(2x)", "sin(2x)"]
        );
        assert_eq!(Hat::new(3).unwrap().names(), ["hat0", "hat1", "hat2"]);
        assert_eq!(Polynomial::new(3).unwrap().names(), ["x", "x^2", "x^3"]);
        assert_eq!(Hat::new(3).unwrap().name(3), None);
    }

    #[test]
    fn constructors_validate() {
        assert!(matches!(
            Harmonic::new(0),
            Err(BasisError::TooSmall { value: 0, min: 1, .. })
        ));
        assert!(matches!(
            Hat::new(2),
            Err(BasisError::TooSmall { value: 2, min: 3, .. })
        ));
        assert!(Polynomial::new(0).is_err());
    }

    #[test]
    fn hat_is_one_at_its_node_and_periodic() {
        let hat = Hat::new(8).unwrap();
        let mut v = [0.0; 8];
        for i in 0..8 {
            hat.eval(hat.node(i), &mut v);
            for (j, &vj) in v.iter().enumerate() {
                let want = if i == j { 1.0 } else { 0.0 };
                assert!((vj - want).abs() < 1e-12, "node {i}, hat{j} = {vj}");
            }
        }
        // Between the last node and +π the last and first hats share the weight.
        let x = PI - TAU / 16.0;
        hat.eval(x, &mut v);
        assert!((v[7] - 0.5).abs() < 1e-12 && (v[0] - 0.5).abs() < 1e-12);
        let mut w = [0.0; 8];
        hat.eval(x - 3.0 * TAU, &mut w);
        for (a, b) in v.iter().zip(&w) {
            assert!((a - b).abs() < 1e-12);
        }
    }

    #[test]
    fn harmonic_values() {
        let h = Harmonic::new(3).unwrap();
        let mut v = [0.0; 6];
        h.eval(0.7, &mut v);
        for k in 1..=3 {
            assert!((v[2 * k - 2] - (k as f64 * 0.7).cos()).abs() < 1e-14);
            assert!((v[2 * k - 1] - (k as f64 * 0.7).sin()).abs() < 1e-14);
        }
    }

    #[test]
    fn nan_poisons() {
        let mut v = [0.0; 8];
        Hat::new(8).unwrap().eval(f64::NAN, &mut v);
        assert!(v.iter().any(|x| x.is_nan()));
        Hat::new(8).unwrap().eval_deriv(f64::INFINITY, &mut v);
        assert!(v.iter().any(|x| x.is_nan()));
    }

    /// A basis that evaluates like `inner` but keeps the provided (quadrature) antiderivative.
    #[derive(Debug)]
    struct Plain<B>(B);

    impl<B: Basis> Basis for Plain<B> {
        fn len(&self) -> usize {
            self.0.len()
        }
        fn name(&self, i: usize) -> Option<String> {
            self.0.name(i)
        }
        fn domain(&self) -> Domain {
            self.0.domain()
        }
        fn eval(&self, x: f64, out: &mut [f64]) {
            self.0.eval(x, out)
        }
        fn eval_deriv(&self, x: f64, out: &mut [f64]) {
            self.0.eval_deriv(x, out)
        }
    }

    /// `Φ(b) − Φ(a)` against `∫_a^b φ` by the midpoint rule on fine steps, and the growth of a
    /// circle basis over whole turns.
    fn check_antiderivative(basis: &dyn Basis, points: &[f64], tol: f64) {
        let n = basis.len();
        let (mut fa, mut fb, mut phi) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        for w in points.windows(2) {
            let (a, b) = (w[0], w[1]);
            basis.eval_antiderivative(a, &mut fa);
            basis.eval_antiderivative(b, &mut fb);
            let steps = 20_000;
            let hstep = (b - a) / steps as f64;
            let mut sum = vec![0.0; n];
            for s in 0..steps {
                basis.eval(a + (s as f64 + 0.5) * hstep, &mut phi);
                for (acc, p) in sum.iter_mut().zip(&phi) {
                    *acc += p * hstep;
                }
            }
            for i in 0..n {
                let got = fb[i] - fa[i];
                assert!(
                    (got - sum[i]).abs() < tol,
                    "{basis:?} function {i} on [{a}, {b}]: {got} against {}",
                    sum[i]
                );
            }
        }
    }

    #[test]
    fn antiderivatives_integrate_the_functions() {
        // Points that cross ±π and whole turns, on the unwrapped angle.
        let circle = [-9.7, -4.0, -3.1, 0.3, 2.9, 3.5, 7.0, 13.3];
        let line = [-2.5, -0.7, 0.0, 0.4, 1.9];
        let hat = Hat::new(7).unwrap();
        let bases: Vec<(Box<dyn Basis>, &[f64])> = vec![
            (Box::new(Harmonic::new(3).unwrap()), &circle),
            (Box::new(hat), &circle),
            (Box::new(Polynomial::new(4).unwrap()), &line),
            (Box::new(Plain(Harmonic::new(2).unwrap())), &circle),
            (Box::new(Plain(Polynomial::new(3).unwrap())), &line),
        ];
        for (basis, points) in &bases {
            check_antiderivative(basis.as_ref(), points, 1e-7);
        }
        // A hat's antiderivative grows by 2π/N per turn; a harmonic's does not grow.
        let mut a = vec![0.0; 7];
        let mut b = vec![0.0; 7];
        hat.eval_antiderivative(0.4, &mut a);
        hat.eval_antiderivative(0.4 + 3.0 * TAU, &mut b);
        for i in 0..7 {
            assert!((b[i] - a[i] - 3.0 * TAU / 7.0).abs() < 1e-12);
        }
        // Through a BasisKind and a reference, the closed form is used.
        let (mut c, mut q) = (vec![0.0; 7], vec![0.0; 7]);
        let kind = BasisKind::from(hat);
        kind.eval_antiderivative(1.0, &mut q);
        hat.eval_antiderivative(1.0, &mut c);
        assert_eq!(c, q);
        Basis::eval_antiderivative(&&kind, 1.0, &mut q);
        assert_eq!(c, q);
        let mut nan = vec![0.0; 7];
        hat.eval_antiderivative(f64::NAN, &mut nan);
        assert!(nan.iter().all(|v| v.is_nan()));
    }

    #[test]
    fn kinds_delegate_and_display() {
        let k: BasisKind = Hat::new(4).unwrap().into();
        assert_eq!(k.len(), 4);
        assert_eq!(k.domain(), Domain::Circle);
        assert_eq!(k.to_string(), "hat (N = 4)");
        let b: Box<dyn Basis> = Box::new(Polynomial::new(2).unwrap());
        assert_eq!(b.domain(), Domain::Line);
        assert_eq!(b.names(), ["x", "x^2"]);
    }
}
