//! The embedding's checks through its public interface, one module per source file (they are
//! here, not unit tests, so that `cargo test` compiles the library's k-d tree searches once).

use std::f64::consts::{PI, TAU};

use embedding::*;

/// Average mutual information: parameters, entropies, the wrap, the first-minimum rule.
mod ami {
    use super::*;

    #[test]
    fn params_are_checked() {
        let p = AmiParams::new(Domain::Line);
        assert!(p.with_bins(1).is_err());
        assert!(p.with_bins(1025).is_err());
        assert!(p.with_max_lag(0).is_err());
        assert_eq!(p.with_bins(2).unwrap().bins(), 2);
        let p = p.with_max_lag(10).unwrap();
        assert!(matches!(
            average_mutual_information(&[0.0, 1.0, 2.0], &p),
            Err(EmbeddingError::LagTooLarge { max_lag: 10, len: 3 })
        ));
        let p = p.with_max_lag(1).unwrap();
        assert!(matches!(
            average_mutual_information(&[2.0; 5], &p),
            Err(EmbeddingError::ConstantSignal { .. })
        ));
        assert!(matches!(
            average_mutual_information(&[0.0, f64::NAN, 1.0], &p),
            Err(EmbeddingError::NonFinite { index: 1, .. })
        ));
    }

    #[test]
    fn lag_zero_is_the_entropy_and_bits_are_nats_over_ln2() {
        // Eight values, one per box of 8: entropy ln 8.
        let x: Vec<f64> = (0..8).map(f64::from).collect();
        let p = AmiParams::new(Domain::Line)
            .with_bins(8)
            .unwrap()
            .with_max_lag(2)
            .unwrap();
        let c = average_mutual_information(&x, &p).unwrap();
        assert!((c.values[0] - 8f64.ln()).abs() < 1e-12);
        let b = average_mutual_information(&x, &p.with_unit(InfoUnit::Bits)).unwrap();
        assert!((b.values[0] - 3.0).abs() < 1e-12);
        assert_eq!(b.unit, InfoUnit::Bits);
    }

    #[test]
    fn independent_boxes_give_zero() {
        // Period-4 pattern a a b b: at lag 1 the pairs (a,a) (a,b) (b,b) (b,a) are equally frequent.
        let x: Vec<f64> = (0..400).map(|k| if k % 4 < 2 { 0.0 } else { 1.0 }).collect();
        let p = AmiParams::new(Domain::Line)
            .with_bins(2)
            .unwrap()
            .with_max_lag(2)
            .unwrap();
        let c = average_mutual_information(&x, &p).unwrap();
        assert!(c.values[1].abs() < 1e-4, "{}", c.values[1]);
        // At lag 2 the box of x_{i+2} is fixed by that of x_i: I is the entropy, ln 2 up to the
        // unequal ends.
        assert!((c.values[2] - 2f64.ln()).abs() < 1e-4, "{}", c.values[2]);
    }

    #[test]
    fn circle_boxes_ignore_the_wrap() {
        // Adding whole turns moves no sample to another box.
        let x: Vec<f64> = (0..500).map(|k| (0.37 * f64::from(k)).sin() * 3.0).collect();
        let y: Vec<f64> = x
            .iter()
            .enumerate()
            .map(|(k, v)| v + TAU * (k % 5) as f64)
            .collect();
        let p = AmiParams::new(Domain::Circle).with_max_lag(5).unwrap();
        assert_eq!(
            average_mutual_information(&x, &p).unwrap(),
            average_mutual_information(&y, &p).unwrap()
        );
    }

    #[test]
    fn first_minimum_rule() {
        let curve = |v: &[f64]| AmiCurve {
            values: v.to_vec(),
            unit: InfoUnit::Nats,
        };
        assert_eq!(curve(&[3.0, 2.0, 1.0, 2.0]).first_minimum(), Some(2));
        assert_eq!(curve(&[3.0, 2.0, 1.0, 1.0, 2.0]).first_minimum(), Some(2));
        assert_eq!(curve(&[3.0, 2.0, 1.0, 1.0, 0.5, 2.0]).first_minimum(), Some(4));
        assert_eq!(curve(&[3.0, 2.0, 1.0]).first_minimum(), None);
        assert_eq!(curve(&[3.0, 2.0, 2.0]).first_minimum(), None);
        assert_eq!(curve(&[1.0, 2.0, 3.0]).first_minimum(), None);
        assert!(matches!(
            curve(&[1.0, 2.0]).delay(),
            Err(EmbeddingError::NoFirstMinimum { max_lag: 1 })
        ));
    }
}

/// Delay vectors.
mod delay {
    use super::*;

    #[test]
    fn vectors_of_a_ramp() {
        let x: Vec<f64> = (0..10).map(f64::from).collect();
        let e = Embedding::new(3, 2).unwrap();
        assert_eq!(e.window(), 5);
        let v = e.vectors(&x).unwrap();
        assert_eq!(v.len(), 6);
        let s = v.get(4).unwrap();
        assert_eq!(s.iter().collect::<Vec<_>>(), vec![4.0, 6.0, 8.0]);
        assert_eq!(s.component(2), Some(8.0));
        assert_eq!(s.component(3), None);
        let mut buf = [0.0; 3];
        v.get(5).unwrap().copy_to(&mut buf);
        assert_eq!(buf, [5.0, 7.0, 9.0]);
        assert!(v.get(6).is_none());
        assert_eq!(v.iter().count(), 6);
        assert_eq!(v.take(2).len(), 2);
        assert_eq!(v.take(100).len(), 6);
    }

    #[test]
    fn invalid_embeddings() {
        assert!(Embedding::new(0, 1).is_err());
        assert!(Embedding::new(1, 0).is_err());
        let e = Embedding::new(4, 3).unwrap();
        assert_eq!(e.count(9), 0);
        assert!(matches!(
            e.vectors(&[0.0; 9]),
            Err(EmbeddingError::TooShort { len: 9, needed: 10 })
        ));
        assert_eq!(e.vectors(&[0.0; 10]).unwrap().len(), 1);
    }
}

/// False nearest neighbours: parameters and a closed curve.
mod fnn {
    use super::*;

    #[test]
    fn params_are_checked() {
        assert!(FnnParams::new(Domain::Line, 0).is_err());
        let p = FnnParams::new(Domain::Circle, 3).unwrap();
        assert!(p.with_max_dim(0).is_err());
        assert!(p.with_max_dim(9).is_err());
        assert!(p.with_ratio_threshold(0.0).is_err());
        assert!(p.with_ratio_threshold(f64::NAN).is_err());
        assert!(p.with_attractor_threshold(Some(-1.0)).is_err());
        assert_eq!(
            p.with_attractor_threshold(None).unwrap().attractor_threshold(),
            None
        );
        assert!(p.with_fraction_threshold(1.0).is_err());
        assert_eq!(p.with_theiler_window(4).theiler_window(), 4);
        assert!(matches!(
            false_nearest_neighbours(&[0.0; 19], &p.with_max_dim(6).unwrap()),
            Err(EmbeddingError::TooShort { len: 19, needed: 20 })
        ));
    }

    #[test]
    fn a_circle_needs_two_dimensions() {
        // x_n = sin(2π n / P), P = 50 φ samples (φ the golden ratio, so that the record never
        // nearly repeats): a closed curve. In one dimension the neighbour of a rising sample is
        // often a falling one (false); in two no neighbour is false.
        let period = 25.0 * (1.0 + 5f64.sqrt());
        let x: Vec<f64> = (0..2000)
            .map(|n| (std::f64::consts::TAU * n as f64 / period).sin())
            .collect();
        let p = FnnParams::new(Domain::Line, 12)
            .unwrap()
            .with_max_dim(3)
            .unwrap()
            .with_theiler_window(5);
        let r = false_nearest_neighbours(&x, &p).unwrap();
        assert!(r.levels[0].fraction() > 0.3, "{:?}", r.levels[0]);
        assert_eq!(r.levels[1].false_neighbours, 0, "{:?}", r.levels[1]);
        assert_eq!(r.minimum_dimension(), Some(2));
        assert_eq!(r.levels[2].points + r.levels[2].unmatched, 2000 - 36);
        // A cutoff below every neighbour distance leaves nothing to count.
        let tiny = p.with_neighbour_cutoff(Some(1e-9)).unwrap();
        assert!(matches!(
            false_nearest_neighbours(&x, &tiny),
            Err(EmbeddingError::NoNeighbours { dim: 1 })
        ));
    }
}

/// The circle metric: the periodic tree and the spread.
mod metric {
    use super::*;

    /// Angles at the ends of the periodic tree's box (its coordinates are the angles shifted by π
    /// into [0, 2π)): the neighbour found is the nearest on the circle, by brute force.
    #[test]
    fn angles_at_the_ends_of_the_trees_box() {
        for v in [-PI, -1e-300, -1e-17, 0.0, PI, 3.0 * PI, -7.0, 1e6] {
            let x = [v, v + 0.1, v + 1.0, v - 0.05, v + 2.5];
            let vectors = Embedding::new(1, 1).unwrap().vectors(&x).unwrap();
            let found = nearest_neighbours(&vectors, Domain::Circle, 0).unwrap();
            for (n, f) in found.iter().enumerate() {
                let best = (0..x.len())
                    .filter(|&m| m != n)
                    .map(|m| Domain::Circle.distance(x[n], x[m]))
                    .fold(f64::INFINITY, f64::min);
                let f = f.unwrap();
                assert!(
                    (f.distance - best).abs() < 1e-9,
                    "v = {v}, n = {n}: {} against {best}",
                    f.distance
                );
            }
        }
    }

    #[test]
    fn spread_values() {
        let x = [1.0, 3.0];
        assert_eq!(spread(Domain::Line, &x), 1.0);
        // Two angles either side of π: the circular mean is π and the spread is 0.1.
        let y = [PI - 0.1, -PI + 0.1];
        assert!((spread(Domain::Circle, &y) - 0.1).abs() < 1e-12);
        let even: Vec<f64> = (0..10_000)
            .map(|k| -PI + TAU * (k as f64 + 0.5) / 10_000.0)
            .collect();
        assert!((spread(Domain::Circle, &even) - PI / 3f64.sqrt()).abs() < 1e-3);
        assert_eq!(spread(Domain::Circle, &[]), 0.0);
    }
}

/// The nearest-neighbour search: the wrap, exact copies, windows, the dimension limit.
mod neighbours {
    use super::*;

    #[test]
    fn neighbour_across_the_wrap() {
        // Linear: 3.1 is nearest to 2.0; on the circle it is nearest to −3.1.
        let x = [3.1, 0.0, 2.0, -3.1];
        let v = Embedding::new(1, 1).unwrap().vectors(&x).unwrap();
        let lin = nearest_neighbours(&v, Domain::Line, 0).unwrap();
        let circ = nearest_neighbours(&v, Domain::Circle, 0).unwrap();
        assert_eq!(lin[0].unwrap().index, 2);
        assert_eq!(circ[0].unwrap().index, 3);
        assert!((circ[0].unwrap().distance - (2.0 * PI - 6.2)).abs() < 1e-12);
    }

    #[test]
    fn duplicates_and_windows() {
        // Points 0, 1 and 2 coincide: none may be the other's neighbour.
        let x = [0.5, 0.5, 0.5, 0.7, 1.5];
        let v = Embedding::new(1, 1).unwrap().vectors(&x).unwrap();
        let nn = nearest_neighbours(&v, Domain::Line, 0).unwrap();
        assert_eq!(nn[0].unwrap().index, 3);
        assert_eq!(nn[4].unwrap().index, 3);
        let nn = nearest_neighbours(&v, Domain::Line, 3).unwrap();
        assert_eq!(nn[0].unwrap().index, 4);
        assert_eq!(nn[2], None);
        assert!(matches!(
            nearest_neighbours(&v, Domain::Line, 4),
            Err(EmbeddingError::TheilerTooLarge { .. })
        ));
        let all_same = [1.0; 6];
        let v = Embedding::new(2, 1).unwrap().vectors(&all_same).unwrap();
        assert!(
            nearest_neighbours(&v, Domain::Circle, 0)
                .unwrap()
                .iter()
                .all(Option::is_none)
        );
    }

    #[test]
    fn quantised_record() {
        // Three levels repeated 1000 times each: the neighbour of every sample is on the next
        // level, at the nearest index outside the window that the ascending copy list offers.
        let x: Vec<f64> = (0..3000).map(|n| f64::from((n % 3) as u8) * 0.25).collect();
        let v = Embedding::new(1, 1).unwrap().vectors(&x).unwrap();
        let nn = nearest_neighbours(&v, Domain::Line, 2).unwrap();
        for (n, nb) in nn.iter().enumerate() {
            let nb = nb.unwrap();
            assert_eq!(nb.distance, 0.25, "n = {n}");
            assert!(nb.index.abs_diff(n) > 2);
        }
    }

    #[test]
    fn dimension_limit() {
        let x: Vec<f64> = (0..20).map(f64::from).collect();
        let v = Embedding::new(9, 1).unwrap().vectors(&x).unwrap();
        assert!(matches!(
            nearest_neighbours(&v, Domain::Line, 0),
            Err(EmbeddingError::InvalidParameter { .. })
        ));
    }
}
