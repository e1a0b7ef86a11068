//! Integration tests: the paper's data set against the classic tool, and the neighbour search
//! against brute force.

mod checks;

use std::f64::consts::{PI, TAU};

use embedding::{
    AmiParams, DelayVectors, Domain, Embedding, FnnParams, Neighbour, average_mutual_information,
    false_nearest_neighbours, nearest_neighbours,
};
use proptest::prelude::*;

const FIXTURE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../../shared/fixtures/paper_dataset.csv"
);

/// TISEAN 3 `false_nearest -d 5 -f 10 -t 0 -M 1,6` on the fixture (rounded to 3 decimals).
const TISEAN_FNN: [f64; 6] = [1.000, 0.776, 0.196, 0.033, 0.014, 0.008];

/// The `theta` column of the fixture (`t,theta`, `#` comments, one header line).
fn paper_theta() -> Vec<f64> {
    let text = std::fs::read_to_string(FIXTURE).expect("fixture readable");
    text.lines()
        .filter(|l| !l.starts_with('#'))
        .skip(1)
        .map(|l| {
            l.split(',')
                .nth(1)
                .expect("theta column")
                .trim()
                .parse()
                .expect("a number")
        })
        .collect()
}

#[test]
fn paper_data_set_delay_and_dimension() {
    let theta = paper_theta();
    assert_eq!(theta.len(), 30_000);

    // TISEAN `mutual -b 16`: first minimum at lag 5, I(5) = 0.0220, I(6) = 0.0225 nats.
    let ami = average_mutual_information(&theta, &AmiParams::new(Domain::Line)).unwrap();
    assert_eq!(ami.delay().unwrap(), 5);
    assert!((ami.values[5] - 0.0220).abs() < 5e-4, "I(5) = {}", ami.values[5]);
    assert!((ami.values[6] - 0.0225).abs() < 5e-4, "I(6) = {}", ami.values[6]);
    let circle_ami = average_mutual_information(&theta, &AmiParams::new(Domain::Circle)).unwrap();
    assert_eq!(circle_ami.delay().unwrap(), 5);

    // Kennel's two tests, linear metric: within 0.01 of TISEAN (which drops distant neighbours
    // instead of applying the attractor-size test; see docs/embedding.md).
    let linear = false_nearest_neighbours(&theta, &FnnParams::new(Domain::Line, 5).unwrap()).unwrap();
    for (level, classic) in linear.levels.iter().zip(TISEAN_FNN) {
        assert!(
            (level.fraction() - classic).abs() < 0.01,
            "d = {}: {} vs {classic}",
            level.dim,
            level.fraction()
        );
    }
    assert_eq!(linear.minimum_dimension(), Some(4));

    // TISEAN's own rule (ratio test only, neighbours beyond R_A / 10 left out): within 0.002.
    let tisean = FnnParams::new(Domain::Line, 5)
        .unwrap()
        .with_max_dim(6)
        .unwrap()
        .with_attractor_threshold(None)
        .unwrap()
        .with_neighbour_cutoff(Some(0.1))
        .unwrap();
    let tisean = false_nearest_neighbours(&theta, &tisean).unwrap();
    for (level, classic) in tisean.levels.iter().zip(TISEAN_FNN) {
        assert!(
            (level.fraction() - classic).abs() < 0.002,
            "d = {}: {} vs {classic}",
            level.dim,
            level.fraction()
        );
    }

    // The circle metric removes the wrap artefacts: lower from d = 4, at least 3 times lower from
    // d = 5, and the same minimum dimension as the paper.
    let circle = false_nearest_neighbours(&theta, &FnnParams::new(Domain::Circle, 5).unwrap()).unwrap();
    for (c, l) in circle.levels.iter().zip(&linear.levels).skip(3) {
        assert!(
            c.fraction() < l.fraction(),
            "d = {}: circle {} linear {}",
            c.dim,
            c.fraction(),
            l.fraction()
        );
        if c.dim >= 5 {
            assert!(
                3.0 * c.fraction() < l.fraction(),
                "d = {}: {} vs {}",
                c.dim,
                c.fraction(),
                l.fraction()
            );
        }
    }
    assert_eq!(circle.minimum_dimension(), Some(4));
}

/// The definition of `nearest_neighbours`, by exhaustive search.
fn brute_force(vectors: &DelayVectors<'_>, metric: Domain, theiler: usize) -> Vec<Option<Neighbour>> {
    vectors
        .iter()
        .enumerate()
        .map(|(n, a)| {
            vectors
                .iter()
                .enumerate()
                .filter(|&(m, _)| m.abs_diff(n) > theiler)
                .map(|(m, b)| Neighbour {
                    index: m,
                    distance: embedding::delay_distance(metric, &a, &b),
                })
                .filter(|nb| nb.distance > 0.0)
                .min_by(|p, q| p.distance.total_cmp(&q.distance))
        })
        .collect()
}

/// Small records: continuous values, or values on a coarse grid (many ties and exact copies,
/// ±π included so that copies across the wrap occur).
fn record() -> impl Strategy<Value = Vec<f64>> {
    prop_oneof![
        prop::collection::vec(-PI..PI, 8..300),
        prop::collection::vec((-4i32..=4).prop_map(|k| f64::from(k) * PI / 4.0), 8..300),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    /// tree search == brute force (compared by distance, since ties may pick either index), and
    /// the index returned is admissible and at the distance returned.
    #[test]
    fn neighbour_search_is_exact(
        x in record(),
        dim in 1usize..=5,
        delay in 1usize..=3,
        theiler in 0usize..=12,
        circle in any::<bool>(),
    ) {
        let metric = if circle { Domain::Circle } else { Domain::Line };
        // A record shorter than one vector's span has no vectors; every longer one has some.
        prop_assume!(x.len() > (dim - 1) * delay);
        let vectors = Embedding::new(dim, delay).unwrap().vectors(&x).unwrap();
        prop_assume!(theiler + 1 < vectors.len());
        let tree = nearest_neighbours(&vectors, metric, theiler).unwrap();
        let brute = brute_force(&vectors, metric, theiler);
        prop_assert_eq!(tree.len(), brute.len());
        for (n, (t, b)) in tree.iter().zip(&brute).enumerate() {
            match (t, b) {
                (None, None) => {}
                (Some(t), Some(b)) => {
                    prop_assert!((t.distance - b.distance).abs() <= 1e-12, "n = {}: {:?} vs {:?}", n, t, b);
                    prop_assert!(t.index.abs_diff(n) > theiler);
                    let d = embedding::delay_distance(metric, &vectors.get(n).unwrap(), &vectors.get(t.index).unwrap());
                    prop_assert_eq!(d, t.distance);
                }
                _ => prop_assert!(false, "n = {}: tree {:?}, brute force {:?}", n, t, b),
            }
        }
    }

    /// FNN with the circle metric does not see whole turns: x and x + 2π k_n give the same counts.
    #[test]
    fn circle_fnn_ignores_turns(x in prop::collection::vec(-PI..PI, 40..120), turns in prop::collection::vec(-3i32..=3, 120)) {
        let params = FnnParams::new(Domain::Circle, 2).unwrap().with_max_dim(3).unwrap();
        let y: Vec<f64> = x.iter().zip(&turns).map(|(v, &k)| v + TAU * f64::from(k)).collect();
        let (a, b) = (false_nearest_neighbours(&x, &params), false_nearest_neighbours(&y, &params));
        // Whole turns must not decide whether FNN succeeds either.
        prop_assert_eq!(a.is_ok(), b.is_ok(), "{:?} vs {:?}", a, b);
        match (a, b) {
            (Ok(a), Ok(b)) => {
                for (p, q) in a.levels.iter().zip(&b.levels) {
                    prop_assert_eq!(p.false_neighbours, q.false_neighbours);
                    prop_assert_eq!(p.points, q.points);
                }
            }
            (a, b) => prop_assert_eq!(a.err(), b.err()),
        }
    }

    /// FNN with the linear metric is scale-free: x and 4x give the same counts (exact in binary).
    #[test]
    fn linear_fnn_is_scale_free(x in prop::collection::vec(-10.0..10.0f64, 40..120)) {
        let params = FnnParams::new(Domain::Line, 1).unwrap().with_max_dim(4).unwrap();
        let y: Vec<f64> = x.iter().map(|v| 4.0 * v).collect();
        let a = false_nearest_neighbours(&x, &params).unwrap();
        let b = false_nearest_neighbours(&y, &params).unwrap();
        for (p, q) in a.levels.iter().zip(&b.levels) {
            prop_assert_eq!(p.false_neighbours, q.false_neighbours);
            prop_assert_eq!(p.ratio_false, q.ratio_false);
            prop_assert_eq!(p.points, q.points);
        }
    }
}
