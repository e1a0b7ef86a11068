//! A compressed system (each group of segments' rows replaced by its triangular factor) is the
//! same least-squares problem: checked on the weak form's windows of the paper's data set.

use circle_signal::SampleClock;
use hb_basis::{BasisKind, Harmonic};
use hb_solve::{
    BootstrapParams, IdentifyParams, LinearSystem, QrSolver, ResampleBlock, SelectParams, SvdSolver,
    WeakForm, bootstrap, build_system, fit_quality, held_out, select_terms,
};

use crate::common::read_paper_dataset;

/// The weak form's system of the paper's data set on windows of three periods, with a library
/// wider than the truth (the harmonic basis K = 2).
fn paper_windows() -> LinearSystem {
    let (t0, x) = read_paper_dataset();
    let clock = SampleClock::nondimensional(25)
        .unwrap()
        .with_start_time(t0)
        .unwrap();
    let segments = upo_search::Windows::new(&clock).unwrap().windows(&x).unwrap();
    let basis: BasisKind = Harmonic::new(2).unwrap().into();
    let params = IdentifyParams::builder(clock).build().unwrap();
    build_system(&basis, &x[..], &segments, &params, &WeakForm::default()).unwrap()
}

/// Coefficients equal to `rel` of the largest of them (a coefficient whose truth is 0 comes out
/// at rounding's size, relative to nothing).
fn same_solution(a: &[f64], b: &[f64], rel: f64) -> bool {
    let scale = a.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    a.iter().zip(b).all(|(u, v)| (u - v).abs() <= rel * scale)
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()).max(1e-300)
}

#[test]
fn a_compressed_system_solves_as_its_rows() {
    let whole = paper_windows();
    for group in [1, 3, 40] {
        let c = whole.clone().compressed(group).unwrap();
        assert!(c.is_compressed());
        assert_eq!(c.blocks().len(), whole.blocks().len().div_ceil(group));
        assert_eq!((c.equations(), c.segments()), (whole.rows(), whole.segments()));
        assert_eq!(c.whirling_segments(), whole.whirling_segments());
        for solver in [
            &QrSolver::default() as &dyn hb_solve::LstsqSolver,
            &SvdSolver::default(),
        ] {
            let (a, b) = (whole.solve(solver).unwrap(), c.solve(solver).unwrap());
            assert_eq!(a.rows, b.rows, "group {group}");
            assert!(
                close(a.rss, b.rss, 1e-8),
                "group {group}: rss {} vs {}",
                a.rss,
                b.rss
            );
            assert!(close(a.condition, b.condition, 1e-8));
            assert!(
                same_solution(&a.solution, &b.solution, 1e-10),
                "group {group}: {:?} vs {:?}",
                a.solution,
                b.solution
            );
            for (u, v) in a.std_errors.iter().zip(&b.std_errors) {
                assert!(close(*u, *v, 1e-7), "group {group}: {u} vs {v}");
            }
            let (qa, qb) = (
                fit_quality(&whole, &a.solution).unwrap(),
                fit_quality(&c, &b.solution).unwrap(),
            );
            assert!(close(qa.unexplained, qb.unexplained, 1e-6));
            assert_eq!(qa.spectrum.len(), qb.spectrum.len());
            for (la, lb) in qa.spectrum.iter().zip(&qb.spectrum) {
                assert_eq!((la.harmonic, la.rows), (lb.harmonic, lb.rows));
                assert!(close(la.rhs_rms, lb.rhs_rms, 1e-9));
                assert!(
                    close(la.residual_rms, lb.residual_rms, 1e-7),
                    "{} vs {}",
                    la.residual_rms,
                    lb.residual_rms
                );
            }
        }
        // A subset of the columns, as the selection of terms refits it.
        let keep = [0, 2, 3];
        let (a, b) = (
            whole
                .with_columns(&keep)
                .unwrap()
                .solve(&QrSolver::default())
                .unwrap(),
            c.with_columns(&keep)
                .unwrap()
                .solve(&QrSolver::default())
                .unwrap(),
        );
        assert!(
            same_solution(&a.solution, &b.solution, 1e-10),
            "group {group}, columns {keep:?}"
        );
    }
    assert!(whole.clone().compressed(0).is_err());
}

#[test]
fn segment_by_segment_compression_keeps_folds_resamples_and_selection() {
    let whole = paper_windows();
    let c = whole.clone().compressed(1).unwrap();
    // Each block is its segment's factor: the folds and the bootstrap's runs are the same.
    assert!(c.rows() < whole.rows());
    let (ha, hb) = (held_out(&whole, 10).unwrap(), held_out(&c, 10).unwrap());
    assert_eq!(ha.folds, hb.folds);
    assert!(
        close(ha.unexplained, hb.unexplained, 1e-6),
        "{} vs {}",
        ha.unexplained,
        hb.unexplained
    );
    let params = BootstrapParams::builder()
        .resamples(200)
        .block(ResampleBlock::Auto)
        .build()
        .unwrap();
    let solver = QrSolver::default();
    let (ba, bb) = (
        bootstrap(&whole, &solver, &params).unwrap(),
        bootstrap(&c, &solver, &params).unwrap(),
    );
    assert_eq!(ba.block, bb.block);
    for (ia, ib) in ba.intervals.iter().zip(&bb.intervals) {
        assert!(
            close(ia.lower, ib.lower, 1e-7) && close(ia.upper, ib.upper, 1e-7),
            "{ia:?} vs {ib:?}"
        );
    }
    let (sa, sb) = (
        select_terms(&whole, &SelectParams::default()).unwrap(),
        select_terms(&c, &SelectParams::default()).unwrap(),
    );
    assert_eq!(sa.kept, sb.kept);
}

#[test]
fn joined_parts_are_the_whole() {
    let whole = paper_windows();
    // The rows twice over, compressed by groups of 5 and of 7: joined, they stand for both.
    let joined = LinearSystem::joined(vec![
        whole.clone().compressed(5).unwrap(),
        whole.clone().compressed(7).unwrap(),
    ])
    .unwrap();
    assert_eq!(joined.equations(), 2 * whole.rows());
    assert_eq!(joined.segments(), 2 * whole.segments());
    let (a, b) = (
        whole.solve(&QrSolver::default()).unwrap(),
        joined.solve(&QrSolver::default()).unwrap(),
    );
    assert!(
        same_solution(&a.solution, &b.solution, 1e-10),
        "{:?} vs {:?}",
        a.solution,
        b.solution
    );
    assert!(close(2.0 * a.rss, b.rss, 1e-8));
    assert!(LinearSystem::joined(Vec::new()).is_err());
    let other = whole.with_columns(&[0, 1]).unwrap();
    assert!(LinearSystem::joined(vec![whole.clone(), other]).is_err());
    // A part that holds its rows joins a compressed one: its rows' spectrum lines are kept.
    let mixed = LinearSystem::joined(vec![whole.clone(), whole.clone().compressed(3).unwrap()]).unwrap();
    let fit = mixed.solve(&QrSolver::default()).unwrap();
    let (q, q1) = (
        fit_quality(&mixed, &fit.solution).unwrap(),
        fit_quality(&whole, &a.solution).unwrap(),
    );
    for (l, l1) in q.spectrum.iter().zip(&q1.spectrum) {
        assert_eq!(l.rows, 2 * l1.rows);
        assert!(close(l.rhs_rms, l1.rhs_rms, 1e-9));
    }
}
