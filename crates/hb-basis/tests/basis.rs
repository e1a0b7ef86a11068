//! Invariants of the bases and accuracy of the planned Fourier coefficients.
use hb_basis::{
    Basis, BasisError, BasisKind, Domain, FourierPlan, FourierPlanner, Harmonic, Hat, Polynomial, Spectrum,
    coefficients_from_bin,
};
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::{PI, TAU};

/// Coefficients by the defining sums, O(L²): a_j = (2/L) Σ s_n cos(2π j n/L), b_j = (2/L) Σ s_n sin(..),
/// halved at the Nyquist harmonic of an even length.
fn naive(s: &[f64], m: usize) -> (Vec<f64>, Vec<f64>) {
    let l = s.len();
    let mut a = vec![0.0; m + 1];
    let mut b = vec![0.0; m + 1];
    for j in 0..=m {
        for (n, &x) in s.iter().enumerate() {
            let arg = TAU * ((j * n) % l) as f64 / l as f64;
            a[j] += x * arg.cos();
            b[j] += x * arg.sin();
        }
        let scale = if 2 * j == l { 1.0 } else { 2.0 } / l as f64;
        a[j] *= scale;
        b[j] *= if 2 * j == l { 0.0 } else { scale };
    }
    (a, b)
}

#[test]
fn planned_coefficients_match_naive_dft() {
    let mut rng = ChaCha8Rng::seed_from_u64(20240611);
    let mut planner = FourierPlanner::new();
    for &l in &[2usize, 3, 7, 25, 50, 64, 75, 101, 400] {
        for _ in 0..3 {
            let s: Vec<f64> = (0..l).map(|_| rng.random_range(-3.0..3.0)).collect();
            let m = l / 2;
            let (want_a, want_b) = naive(&s, m);
            let plan = planner.plan(l).unwrap();
            let (mut a, mut b) = (vec![0.0; m + 1], vec![0.0; m + 1]);
            plan.coefficients(&s, &mut a, &mut b).unwrap();
            for j in 0..=m {
                assert!(
                    (a[j] - want_a[j]).abs() < 1e-12,
                    "L = {l}, a_{j}: {} vs {}",
                    a[j],
                    want_a[j]
                );
                assert!(
                    (b[j] - want_b[j]).abs() < 1e-12,
                    "L = {l}, b_{j}: {} vs {}",
                    b[j],
                    want_b[j]
                );
            }
        }
    }
}

#[test]
fn modulated_bins_equal_transforms_of_modulated_segments() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    for &(l, k) in &[(25usize, 1usize), (50, 2), (75, 3), (24, 1), (400, 16)] {
        let s: Vec<f64> = (0..l).map(|_| rng.random_range(-1.0..1.0)).collect();
        let phase = rng.random_range(-1e3..1e3);
        let cos_mod: Vec<f64> = s
            .iter()
            .enumerate()
            .map(|(n, &x)| x * (phase + TAU * (k * n) as f64 / l as f64).cos())
            .collect();
        let sin_mod: Vec<f64> = s
            .iter()
            .enumerate()
            .map(|(n, &x)| x * (phase + TAU * (k * n) as f64 / l as f64).sin())
            .collect();
        let mut plan = FourierPlan::new(l).unwrap();
        let bins = plan.transform(&s).unwrap().bins().to_vec();
        let spec = Spectrum::new(&bins, l).unwrap();
        let cos_bins = plan.transform(&cos_mod).unwrap().bins().to_vec();
        let sin_bins = plan.transform(&sin_mod).unwrap().bins().to_vec();
        for j in 0..=l / 2 {
            let (c, s) = spec.modulated_bins(
                j as isize,
                k as isize,
                hb_basis::Complex64::from_polar(1.0, phase),
            );
            assert!(
                (c - cos_bins[j]).norm() < 1e-11,
                "L = {l}, j = {j}: {c} vs {}",
                cos_bins[j]
            );
            assert!(
                (s - sin_bins[j]).norm() < 1e-11,
                "L = {l}, j = {j}: {s} vs {}",
                sin_bins[j]
            );
            let (a1, b1) = coefficients_from_bin(c, j, l);
            let (a2, b2) = coefficients_from_bin(cos_bins[j], j, l);
            assert!((a1 - a2).abs() < 1e-12 && (b1 - b2).abs() < 1e-12);
        }
    }
}

#[test]
fn spectrum_symmetry() {
    let s = [1.0, -2.0, 0.5, 3.0, 0.25];
    let mut plan = FourierPlan::new(5).unwrap();
    let spec = plan.transform(&s).unwrap();
    for j in -7isize..7 {
        let direct: hb_basis::Complex64 = s
            .iter()
            .enumerate()
            .map(|(n, &x)| {
                let arg = -TAU * (j * n as isize) as f64 / 5.0;
                hb_basis::Complex64::new(x * arg.cos(), x * arg.sin())
            })
            .sum();
        assert!((spec.bin(j) - direct).norm() < 1e-12, "bin {j}");
    }
    assert!(spec.coefficients(3).is_none());
}

#[test]
fn bases_round_trip_through_serde() {
    let kinds: [BasisKind; 3] = [
        Harmonic::new(2).unwrap().into(),
        Hat::new(8).unwrap().into(),
        Polynomial::new(3).unwrap().into(),
    ];
    for k in kinds {
        let json = serde_json::to_string(&k).unwrap();
        assert_eq!(serde_json::from_str::<BasisKind>(&json).unwrap(), k);
        let bytes = postcard::to_stdvec(&k).unwrap();
        assert_eq!(postcard::from_bytes::<BasisKind>(&bytes).unwrap(), k);
    }
    assert_eq!(
        serde_json::to_string(&BasisKind::from(Hat::new(8).unwrap())).unwrap(),
        r#"{"hat":{"nodes":8}}"#
    );
    // Sizes are validated when read.
    assert!(serde_json::from_str::<BasisKind>(r#"{"hat":{"nodes":2}}"#).is_err());
    assert!(serde_json::from_str::<BasisKind>(r#"{"harmonic":{"order":0}}"#).is_err());
}

/// `Σ c_i hat_i(x)`.
fn hat_curve(hat: &Hat, c: &[f64], x: f64) -> f64 {
    let mut phi = vec![0.0; hat.len()];
    hat.eval(x, &mut phi);
    phi.iter().zip(c).map(|(p, c)| p * c).sum()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// A curve already in the span of the hats is its own projection.
    #[test]
    fn hat_projection_of_a_hat_curve_is_exact(
        c in prop::collection::vec(-5.0..5.0f64, 3..40),
        extra in 0usize..500,
    ) {
        let hat = Hat::new(c.len()).unwrap();
        let points = 2 * c.len() + extra;
        let got = hat.project(points, |x| hat_curve(&hat, &c, x)).unwrap();
        for (i, (g, w)) in got.iter().zip(&c).enumerate() {
            prop_assert!((g - w).abs() < 1e-11, "c[{}] = {} against {}", i, g, w);
        }
    }

    /// The residual of a projection is orthogonal to every hat in the quadrature's inner product,
    /// and no other hat curve, the interpolant at the nodes among them, is closer in that norm.
    #[test]
    fn hat_projection_residual_is_orthogonal_to_every_hat(
        nodes in 3usize..30,
        extra in 0usize..2000,
        a in -2.0..2.0f64,
        k in 1u32..6,
        phase in -PI..PI,
    ) {
        let hat = Hat::new(nodes).unwrap();
        let points = 2 * nodes + extra;
        let f = |x: f64| a * (f64::from(k) * x + phase).sin() + (x.cos() - 0.3).exp();
        let c = hat.project(points, f).unwrap();
        let grid: Vec<f64> = (0..points).map(|s| -PI + TAU * (s as f64 + 0.5) / points as f64).collect();
        let residual: Vec<f64> = grid.iter().map(|&x| f(x) - hat_curve(&hat, &c, x)).collect();
        let scale: f64 = grid.iter().map(|&x| f(x).abs()).sum();
        let mut phi = vec![0.0; nodes];
        for j in 0..nodes {
            let dot: f64 = grid
                .iter()
                .zip(&residual)
                .map(|(&x, r)| {
                    hat.eval(x, &mut phi);
                    r * phi[j]
                })
                .sum();
            prop_assert!(dot.abs() <= 1e-12 * scale, "hat {}: {} (scale {})", j, dot, scale);
        }
        let norm = |coef: &[f64]| -> f64 { grid.iter().map(|&x| (f(x) - hat_curve(&hat, coef, x)).powi(2)).sum() };
        let interpolant: Vec<f64> = (0..nodes).map(|i| f(hat.node(i))).collect();
        prop_assert!(norm(&c) <= norm(&interpolant) * (1.0 + 1e-12));
    }
}

#[test]
fn hat_projection_needs_two_points_per_interval_and_a_finite_function() {
    let hat = Hat::new(8).unwrap();
    assert!(matches!(
        hat.project(15, f64::sin),
        Err(BasisError::TooSmall {
            value: 15,
            min: 16,
            ..
        })
    ));
    assert!(hat.project(16, f64::sin).is_ok());
    assert!(matches!(
        hat.project(100, |x| if x > 1.0 { f64::NAN } else { x }),
        Err(BasisError::NonFinite { .. })
    ));
}

fn all_bases() -> Vec<Box<dyn Basis>> {
    vec![
        Box::new(Harmonic::new(1).unwrap()),
        Box::new(Harmonic::new(4).unwrap()),
        Box::new(Hat::new(3).unwrap()),
        Box::new(Hat::new(8).unwrap()),
        Box::new(Hat::new(13).unwrap()),
        Box::new(Polynomial::new(1).unwrap()),
        Box::new(Polynomial::new(5).unwrap()),
    ]
}

/// Distance from x to the nearest kink of a basis (hat nodes), or infinity.
fn distance_to_kink(b: &dyn Basis, x: f64) -> f64 {
    let n = b.len();
    if b.domain() == Domain::Circle && b.name(0).as_deref() == Some("hat0") {
        let d = TAU / n as f64;
        let pos = (x + PI).rem_euclid(d);
        pos.min(d - pos)
    } else {
        f64::INFINITY
    }
}

proptest! {
    #[test]
    fn hats_sum_to_one_and_lie_in_unit_interval(nodes in 3usize..40, x in -50.0..50.0f64) {
        let hat = Hat::new(nodes).unwrap();
        let mut v = vec![0.0; nodes];
        hat.eval(x, &mut v);
        let sum: f64 = v.iter().sum();
        prop_assert!((sum - 1.0).abs() <= 1e-12, "sum {}", sum);
        prop_assert!(v.iter().all(|&h| (0.0..=1.0).contains(&h)));
        // At most two hats are non-zero, and they are neighbours on the circle.
        let nz: Vec<usize> = (0..nodes).filter(|&i| v[i] != 0.0).collect();
        prop_assert!(nz.len() <= 2);
        if nz.len() == 2 {
            prop_assert!(nz[1] == nz[0] + 1 || (nz[0] == 0 && nz[1] == nodes - 1));
        }
        // Derivatives of a partition of unity sum to zero.
        hat.eval_deriv(x, &mut v);
        prop_assert!(v.iter().sum::<f64>().abs() <= 1e-12);
    }

    #[test]
    fn derivatives_match_central_differences(x in -3.0..3.0f64) {
        let e = 1e-6;
        for b in all_bases() {
            if distance_to_kink(b.as_ref(), x) < 10.0 * e {
                continue;
            }
            let n = b.len();
            let (mut plus, mut minus, mut d) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
            b.eval(x + e, &mut plus);
            b.eval(x - e, &mut minus);
            b.eval_deriv(x, &mut d);
            for i in 0..n {
                let fd = (plus[i] - minus[i]) / (2.0 * e);
                let scale = 1.0 + d[i].abs();
                prop_assert!((fd - d[i]).abs() <= 1e-6 * scale, "{:?} {}: fd {} vs {}", b, i, fd, d[i]);
            }
        }
    }

    #[test]
    fn circle_bases_are_periodic(x in -3.2..3.2f64, turns in -20i32..20) {
        for b in all_bases().into_iter().filter(|b| b.domain() == Domain::Circle) {
            let n = b.len();
            let (mut v, mut w) = (vec![0.0; n], vec![0.0; n]);
            b.eval(x, &mut v);
            b.eval(x + TAU * turns as f64, &mut w);
            for i in 0..n {
                prop_assert!((v[i] - w[i]).abs() <= 1e-9, "{:?} {}", b, i);
            }
        }
    }
}
