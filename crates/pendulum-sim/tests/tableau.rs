//! The Butcher tableau of DOP853 as the integrator uses it: each stage is evaluated at its node,
//! and each row of the Runge–Kutta matrix sums to that node. (That the matrix is strictly lower
//! triangular and that the weights sum to one and the error estimators' to zero is checked when
//! the library compiles, in `src/tableau.rs`.)
use std::cell::RefCell;

use pendulum_sim::{Dop853, OdeSystem, Tolerances};

/// The nodes `c_i` of the 16 stages (dense output included), as published by Hairer and Wanner.
#[allow(clippy::excessive_precision, clippy::unreadable_literal)]
const NODES: [f64; 16] = [
    0.0,
    0.526001519587677318785587544488e-01,
    0.789002279381515978178381316732e-01,
    0.118350341907227396726757197510,
    0.281649658092772603273242802490,
    0.333333333333333333333333333333,
    0.25,
    0.307692307692307692307692307692,
    0.651282051282051282051282051282,
    0.6,
    0.857142857142857142857142857142,
    1.0,
    1.0,
    0.1,
    0.2,
    0.777777777777777777777777777778,
];

/// `y0' = 1`, `y1' = 0`, recording `(t, y0)` at every evaluation of the right-hand side.
#[derive(Default)]
struct Recorder {
    calls: RefCell<Vec<(f64, f64)>>,
}

impl OdeSystem<2> for Recorder {
    fn rhs(&self, t: f64, y: &[f64; 2], dy: &mut [f64; 2]) {
        self.calls.borrow_mut().push((t, y[0]));
        *dy = [1.0, 0.0];
    }
}

#[test]
fn rows_are_consistent_with_nodes() {
    // For an explicit Runge–Kutta method each row of A sums to its node: c_i = sum_j a_ij. Every
    // stage derivative of y0 is 1, so in a step of length 1 from (0, 0) stage i is evaluated at
    // t = c_i with y0 = sum_j a_ij: t − y0 is c_i − sum_j a_ij. (The second component, 1e6,
    // makes the initial step longer than 1, so `step(1.0)` takes a step of exactly 1.)
    let tol = Tolerances::new(0.5, 1e3).unwrap();
    let mut ode = Dop853::new(Recorder::default(), 0.0, [0.0, 1e6], tol).unwrap();
    assert_eq!(ode.step(1.0).unwrap(), 1.0);
    // The extra stages 13..15 of the dense output are evaluated at the first interpolation.
    ode.interpolate(0.5);
    assert_eq!(ode.stats().rejected, 0);
    let calls = ode.system().calls.borrow();
    // Stage 0 at the start, the initial step's trial evaluation, stages 1..11 of the step, stage
    // 12 (the solution at the step's end), stages 13..15 of the dense output.
    assert_eq!(calls.len(), 17, "{calls:?}");
    let stages = std::iter::once(calls[0]).chain(calls[2..].iter().copied());
    for (i, (t, y0)) in stages.enumerate() {
        assert!(
            (t - NODES[i]).abs() < 1e-13,
            "stage {i} at t = {t}, node {}",
            NODES[i]
        );
        assert!((t - y0).abs() < 1e-13, "row {i}: {y0} vs {t}");
    }
}
