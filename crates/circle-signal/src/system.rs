//! The state traits every system shares, whatever crate defines it: a forced second-order
//! oscillator `x'' = F(t, x, x')` ([`SecondOrderSystem`]), a system of several coordinates solved
//! for its accelerations ([`MultiSystem`]), the branches of a system that switches at rest
//! ([`Branch`]), and the error of a mass matrix that cannot be solved ([`SingularMass`]).
//!
//! They sit in this vocabulary crate so that a simulated system (`pendulum_sim`), an identified
//! model (`hb_model`) and anything a user writes meet on them without one of those crates
//! depending on the other; `pendulum_sim` integrates them and re-exports them under its own
//! paths.
//!
//! # Example
//!
//! ```
//! use circle_signal::system::{MultiSystem, OneCoordinate, SecondOrderSystem};
//!
//! // A linear oscillator x'' = −x − 0.1 x'.
//! struct Spring;
//! impl SecondOrderSystem for Spring {
//!     fn acceleration(&self, _t: f64, x: f64, v: f64) -> f64 {
//!         -x - 0.1 * v
//!     }
//!     fn jacobian(&self, _t: f64, _x: f64, _v: f64) -> [f64; 2] {
//!         [-1.0, -0.1]
//!     }
//! }
//! // The same as a system of one coordinate.
//! let mut acc = [0.0];
//! OneCoordinate(Spring).accelerations(0.0, &[1.0], &[2.0], &mut acc)?;
//! assert_eq!(acc[0], -1.2);
//! # Ok::<(), circle_signal::system::SingularMass>(())
//! ```

/// A forced second-order oscillator `x'' = F(t, x, x')`.
///
/// Both the true pendulum and every identified model implement this, so they run through the
/// same integrator, stroboscopic sampler and Lyapunov estimator (`pendulum_sim`'s).
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

/// The largest number of coordinates of a [`MultiSystem`] (its first-order state has twice as
/// many components, each size compiled once).
pub const MAX_COORDINATES: usize = 8;

/// The mass matrix of a system cannot be solved at time `t`: it is singular, or not positive
/// definite, at the state reached.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[error("the mass matrix is singular at t = {} (relative pivot {pivot:e})", crate::Shown(*.t))]
pub struct SingularMass {
    /// The time of the evaluation.
    pub t: f64,
    /// The pivot of the factorisation that failed, relative to the matrix's scale (for a 2×2
    /// matrix its determinant over the product of its diagonal): zero or negative, or too small
    /// to divide by.
    pub pivot: f64,
}

/// A system of `n` second-order equations solved for the accelerations, `q'' = A(t, q, q')`
/// (see `pendulum_sim::multi`, which integrates it).
///
/// Object safe: the integrators take it as `&dyn MultiSystem`, so each size of state is compiled
/// once whatever the system.
pub trait MultiSystem {
    /// The number of coordinates `n` (`1..=`[`MAX_COORDINATES`]).
    fn coordinates(&self) -> usize;

    /// The accelerations `q''` at `(t, q, q')` into `acc` (each slice of length `n`), with
    /// `sign(0) = 0` for a dry-friction term. Errors where the mass matrix is singular there.
    fn accelerations(&self, t: f64, q: &[f64], v: &[f64], acc: &mut [f64]) -> Result<(), SingularMass>;

    /// Whether coordinate `c`'s equation has terms in `sign(q_c')` or `|q_c'|` (dry friction,
    /// quadratic drag). Default: no.
    fn switches_at_rest(&self, c: usize) -> bool {
        let _ = c;
        false
    }

    /// The accelerations with `sign(q_c')` taken as `signs[c]` and `|q_c'|` as `signs[c] · q_c'`
    /// for every coordinate `c` that switches at rest (`signs[c]` is `±1` on a branch, or a held
    /// value in `[−1, 1]` while the coordinate sticks); `signs[c]` is to be ignored for the other
    /// coordinates. Smooth in `v` on each branch, and affine in the signs (each sign in terms of
    /// its own, never a product of two). Default: [`accelerations`](Self::accelerations), for a
    /// system with no such terms.
    fn accelerations_with_signs(
        &self,
        t: f64,
        q: &[f64],
        v: &[f64],
        signs: &[f64],
        acc: &mut [f64],
    ) -> Result<(), SingularMass> {
        let _ = signs;
        self.accelerations(t, q, v, acc)
    }
}

impl<S: MultiSystem + ?Sized> MultiSystem for &S {
    fn coordinates(&self) -> usize {
        (**self).coordinates()
    }
    fn accelerations(&self, t: f64, q: &[f64], v: &[f64], acc: &mut [f64]) -> Result<(), SingularMass> {
        (**self).accelerations(t, q, v, acc)
    }
    fn switches_at_rest(&self, c: usize) -> bool {
        (**self).switches_at_rest(c)
    }
    fn accelerations_with_signs(
        &self,
        t: f64,
        q: &[f64],
        v: &[f64],
        signs: &[f64],
        acc: &mut [f64],
    ) -> Result<(), SingularMass> {
        (**self).accelerations_with_signs(t, q, v, signs, acc)
    }
}

/// A one-coordinate [`SecondOrderSystem`] as a [`MultiSystem`] with `n = 1`: the acceleration
/// `F(t, x, x')`, its branches `sign(x') = ±1` as [`SecondOrderSystem::acceleration_on`] gives
/// them, and a held value `s` in between as `((1 + s) F_+ + (1 − s) F_−) / 2`, exact at rest for
/// an `F` affine in `sign(x')` (where `|x'| = 0`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OneCoordinate<S>(pub S);

impl<S: SecondOrderSystem> MultiSystem for OneCoordinate<S> {
    fn coordinates(&self) -> usize {
        1
    }
    fn accelerations(&self, t: f64, q: &[f64], v: &[f64], acc: &mut [f64]) -> Result<(), SingularMass> {
        acc[0] = self.0.acceleration(t, q[0], v[0]);
        Ok(())
    }
    fn switches_at_rest(&self, _c: usize) -> bool {
        self.0.switches_at_rest()
    }
    fn accelerations_with_signs(
        &self,
        t: f64,
        q: &[f64],
        v: &[f64],
        signs: &[f64],
        acc: &mut [f64],
    ) -> Result<(), SingularMass> {
        let s = signs[0];
        acc[0] = if s == 1.0 {
            self.0.acceleration_on(Branch::Forward, t, q[0], v[0])
        } else if s == -1.0 {
            self.0.acceleration_on(Branch::Backward, t, q[0], v[0])
        } else {
            let forward = self.0.acceleration_on(Branch::Forward, t, q[0], v[0]);
            let backward = self.0.acceleration_on(Branch::Backward, t, q[0], v[0]);
            0.5 * ((1.0 + s) * forward + (1.0 - s) * backward)
        };
        Ok(())
    }
}
