//! Second-order systems `x'' = F(t, x, x')`: the trait every system implements (the oscillators
//! of this crate, a system in a record's frame, every identified model), and the branches of a
//! system that switches at rest.

/// A forced second-order oscillator `x'' = F(t, x, x')`.
///
/// Both the true pendulum and every identified model implement this, so they run through the
/// same integrator, stroboscopic sampler and Lyapunov estimator.
///
/// A system whose `F` has terms in `sign(x')` or `|x'|` (dry friction, quadratic drag) says so
/// with [`switches_at_rest`](Self::switches_at_rest) and gives its two smooth branches
/// ([`acceleration_on`](Self::acceleration_on), [`jacobian_on`](Self::jacobian_on)): the
/// integrators of this crate then integrate each side of `x' = 0` on its own branch, locate every
/// `x' = 0` and decide there whether the motion reverses or sticks (see the crate documentation).
/// A smooth system needs none of the three.
pub trait SecondOrderSystem {
    /// The acceleration `F(t, x, v)` (with `sign(0) = 0` for a term in `sign(x')`).
    fn acceleration(&self, t: f64, x: f64, v: f64) -> f64;

    /// The partial derivatives `[∂F/∂x, ∂F/∂v]` at `(t, x, v)`, for tangent-linear integration
    /// (away from `v = 0` for a system that switches there).
    fn jacobian(&self, t: f64, x: f64, v: f64) -> [f64; 2];

    /// Whether `F` is not smooth at `x' = 0` (default: smooth).
    fn switches_at_rest(&self) -> bool {
        false
    }

    /// `F` on a branch: `sign(x')` taken as the branch's sign and `|x'|` as `sign · x'`, a function
    /// smooth in `v` that equals `F` on the branch's side of `v = 0`. Default: `F`.
    fn acceleration_on(&self, branch: Branch, t: f64, x: f64, v: f64) -> f64 {
        let _ = branch;
        self.acceleration(t, x, v)
    }

    /// The partial derivatives of [`acceleration_on`](Self::acceleration_on). Default: the
    /// [`jacobian`](Self::jacobian).
    fn jacobian_on(&self, branch: Branch, t: f64, x: f64, v: f64) -> [f64; 2] {
        let _ = branch;
        self.jacobian(t, x, v)
    }
}

/// A side of `x' = 0`: where the velocity is positive, or negative.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Branch {
    /// `x' > 0`: `sign(x') = 1`.
    Forward,
    /// `x' < 0`: `sign(x') = −1`.
    Backward,
}

impl Branch {
    /// `1` or `−1`.
    #[inline]
    pub fn sign(self) -> f64 {
        match self {
            Self::Forward => 1.0,
            Self::Backward => -1.0,
        }
    }

    /// The branch of a non-zero velocity; `None` for `v = 0` (or NaN).
    pub fn of(v: f64) -> Option<Self> {
        if v > 0.0 {
            Some(Self::Forward)
        } else if v < 0.0 {
            Some(Self::Backward)
        } else {
            None
        }
    }

    /// The other side.
    pub fn reversed(self) -> Self {
        match self {
            Self::Forward => Self::Backward,
            Self::Backward => Self::Forward,
        }
    }
}

impl<S: SecondOrderSystem + ?Sized> SecondOrderSystem for &S {
    fn acceleration(&self, t: f64, x: f64, v: f64) -> f64 {
        (**self).acceleration(t, x, v)
    }
    fn jacobian(&self, t: f64, x: f64, v: f64) -> [f64; 2] {
        (**self).jacobian(t, x, v)
    }
    fn switches_at_rest(&self) -> bool {
        (**self).switches_at_rest()
    }
    fn acceleration_on(&self, branch: Branch, t: f64, x: f64, v: f64) -> f64 {
        (**self).acceleration_on(branch, t, x, v)
    }
    fn jacobian_on(&self, branch: Branch, t: f64, x: f64, v: f64) -> [f64; 2] {
        (**self).jacobian_on(branch, t, x, v)
    }
}
