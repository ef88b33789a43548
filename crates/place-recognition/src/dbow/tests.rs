//! Tests of the vocabulary tree and the database on generated descriptor sets.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::*;

fn random_descriptor(rng: &mut ChaCha8Rng) -> Bits512 {
    BinaryDescriptor(std::array::from_fn(|_| rng.random()))
}

/// Descriptors around `prototypes.len()` prototypes: each a prototype with ~`flips` random
/// bits flipped, so the data has cluster structure.
fn noisy(prototypes: &[Bits512], flips: usize, rng: &mut ChaCha8Rng) -> Bits512 {
    let mut d = prototypes[rng.random_range(0..prototypes.len())];
    for _ in 0..flips {
        let b = rng.random_range(0..512);
        d.set_bit(b, !d.bit(b));
    }
    d
}

/// `n` images of `per_image` descriptors each; each image draws from a random subset of the
/// prototypes so that words are unevenly spread over images.
fn images(n: usize, per_image: usize, seed: u64) -> Vec<Vec<Bits512>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let prototypes: Vec<Bits512> = (0..60).map(|_| random_descriptor(&mut rng)).collect();
    (0..n)
        .map(|_| {
            let start = rng.random_range(0..40);
            let subset = &prototypes[start..start + 20];
            (0..per_image)
                .map(|_| noisy(subset, 20, &mut rng))
                .collect()
        })
        .collect()
}

fn vocabulary() -> BinaryVocabulary {
    BinaryVocabulary::train(&images(30, 50, 1), &VocabularyConfig::default(), 7).unwrap()
}

use crate::BinaryDescriptor;

#[test]
fn training_is_deterministic_across_thread_counts() {
    let data = images(30, 50, 1);
    let config = VocabularyConfig::default();
    let a = BinaryVocabulary::train(&data, &config, 7).unwrap();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let b = pool.install(|| BinaryVocabulary::train(&data, &config, 7).unwrap());
    assert_eq!(a, b);
    let c = BinaryVocabulary::train(&data, &config, 8).unwrap();
    assert_ne!(a, c, "another seed gives another tree");
    assert!(a.word_count() > 100, "{a:?}");
    assert!(a.node_count() > a.word_count());
}

#[test]
fn training_descriptors_descend_to_their_leaf_and_idf_counts_images() {
    let data = images(30, 50, 2);
    let (voc, words) =
        BinaryVocabulary::train_with_words(&data, &VocabularyConfig::default(), 3).unwrap();
    let flat: Vec<Bits512> = data.iter().flatten().copied().collect();
    for (d, &w) in flat.iter().zip(&words) {
        assert_eq!(voc.word(d), w);
    }
    // Reference idf: ln(N / n_i), n_i = images with a descriptor in word i.
    let mut images_of = vec![std::collections::BTreeSet::new(); voc.word_count()];
    let mut k = 0;
    for (j, image) in data.iter().enumerate() {
        for _ in image {
            images_of[words[k] as usize].insert(j);
            k += 1;
        }
    }
    for (w, set) in images_of.iter().enumerate() {
        assert!(!set.is_empty(), "every word holds a training descriptor");
        let expected = (data.len() as f64 / set.len() as f64).ln();
        assert!((voc.idf(w as u32).unwrap() - expected).abs() < 1e-12);
    }
}

#[test]
fn small_nodes_are_words_and_bad_input_is_an_error() {
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    let few: Vec<Bits512> = (0..10).map(|_| random_descriptor(&mut rng)).collect();
    let voc = BinaryVocabulary::train(std::slice::from_ref(&few), &VocabularyConfig::default(), 0)
        .unwrap();
    assert_eq!((voc.word_count(), voc.node_count()), (1, 1));
    let equal = vec![few[0]; 50];
    let voc = BinaryVocabulary::train(&[equal], &VocabularyConfig::default(), 0).unwrap();
    assert_eq!(voc.word_count(), 1);
    assert!(BinaryVocabulary::train(&[vec![]], &VocabularyConfig::default(), 0).is_err());
    let bad = VocabularyConfig {
        branching: 1,
        ..VocabularyConfig::default()
    };
    assert!(BinaryVocabulary::train(&[few], &bad, 0).is_err());
}

#[test]
fn transform_gives_normalised_tf_idf_and_a_complete_direct_index() {
    let voc = vocabulary();
    let image = &images(1, 80, 9)[0];
    let (bow, di) = voc.transform(image, 2);
    assert!(!bow.is_empty());
    let sum: f64 = bow.entries().iter().map(|e| e.1).sum();
    assert!((sum - 1.0).abs() < 1e-12);
    assert!(bow.entries().windows(2).all(|p| p[0].0 < p[1].0));
    // Proportional to count · idf.
    let mut count = vec![0.0; voc.word_count()];
    for d in image {
        count[voc.word(d) as usize] += 1.0;
    }
    let total: f64 = (0..voc.word_count())
        .map(|w| count[w] * voc.idf(w as u32).unwrap())
        .sum();
    for &(w, v) in bow.entries() {
        let expected = count[w as usize] * voc.idf(w).unwrap() / total;
        assert!((v - expected).abs() < 1e-12);
    }
    let mut all: Vec<u32> = di.entries().iter().flat_map(|e| e.1.clone()).collect();
    all.sort_unstable();
    assert_eq!(all, (0..image.len() as u32).collect::<Vec<_>>());
    let (_, root) = voc.transform(image, 0);
    assert_eq!(root.entries().len(), 1);
    assert_eq!(root.features(0).len(), image.len());
    assert!(voc.transform(&[], 2).0.is_empty());
}

/// Dense reference: 1 − ½ |a − b|_1 over full-length vectors.
fn dense_score(voc: &BinaryVocabulary, a: &BowVector, b: &BowVector) -> f64 {
    let mut da = vec![0.0; voc.word_count()];
    let mut db = vec![0.0; voc.word_count()];
    for &(w, v) in a.entries() {
        da[w as usize] = v;
    }
    for &(w, v) in b.entries() {
        db[w as usize] = v;
    }
    let l1: f64 = da.iter().zip(&db).map(|(x, y)| (x - y).abs()).sum();
    1.0 - 0.5 * l1
}

fn database(normalise: bool) -> (Dbow, Vec<Vec<Bits512>>) {
    let config = DbowConfig {
        normalise_by_previous: normalise,
        ..DbowConfig::default()
    };
    let mut db = Dbow::new(vocabulary(), config);
    let data = images(25, 40, 11);
    for image in &data {
        let d = db.describe_descriptors(Vec::new(), image);
        db.insert(d);
    }
    (db, data)
}

#[test]
fn inverted_index_scores_equal_brute_force_and_lie_in_unit_interval() {
    let (db, _) = database(false);
    let query = db.describe_descriptors(Vec::new(), &images(1, 40, 12)[0]);
    let candidates = db.query(&query, db.len());
    assert!(!candidates.is_empty());
    for f in 0..db.len() {
        let stored = &db.description(f).unwrap().bow;
        let reference = dense_score(db.vocabulary(), &query.bow, stored);
        let got = candidates
            .iter()
            .find(|c| c.frame == f)
            .map_or(0.0, |c| c.score);
        assert!(
            (got - reference).abs() < 1e-12,
            "frame {f}: {got} vs {reference}"
        );
        assert!((0.0..=1.0).contains(&got));
        assert!((query.bow.score(stored) - reference).abs() < 1e-12);
    }
    assert!((query.bow.score(&query.bow) - 1.0).abs() < 1e-12);
    assert_eq!(query.bow.score(&BowVector::default()), 0.0);
}

#[test]
fn stored_frames_retrieve_themselves_first_and_before_is_respected() {
    let (db, _) = database(false);
    for i in 0..db.len() {
        let c = db.query_stored(i, db.len());
        let best = c.iter().max_by(|a, b| a.score.total_cmp(&b.score)).unwrap();
        assert_eq!((best.frame, best.score), (i, 1.0));
        assert!(c.iter().all(|c| c.frame == i || c.score < 1.0));
        let limited = db.query_stored(i, i);
        assert!(limited.iter().all(|c| c.frame < i));
        for l in &limited {
            assert!(c.iter().any(|c| c == l));
        }
    }
    assert!(db.query_stored(3, 0).is_empty());
    assert!(db.query_stored(db.len(), db.len()).is_empty());
    let empty = db.describe_descriptors(Vec::new(), &[]);
    assert!(db.query(&empty, db.len()).is_empty());
}

#[test]
fn normalised_score_divides_by_the_previous_frame() {
    let (plain, _) = database(false);
    let (eta, _) = database(true);
    assert!(
        eta.query_stored(0, eta.len()).is_empty(),
        "no previous frame"
    );
    for i in 1..eta.len() {
        let bow = &plain.description(i).unwrap().bow;
        let s_prev = bow.score(&plain.description(i - 1).unwrap().bow);
        let p = plain.query_stored(i, plain.len());
        let e = eta.query_stored(i, eta.len());
        assert_eq!(p.len(), e.len());
        for (p, e) in p.iter().zip(&e) {
            assert_eq!(p.frame, e.frame);
            assert!((p.score / s_prev - e.score).abs() < 1e-12);
        }
    }
}

#[test]
fn vocabulary_round_trips_through_json_and_rejects_broken_trees() {
    let voc = vocabulary();
    let mut json = Vec::new();
    voc.to_writer(&mut json).unwrap();
    let back = BinaryVocabulary::from_reader(json.as_slice()).unwrap();
    assert_eq!(voc, back);
    let text = String::from_utf8(json).unwrap();
    let broken = text.replacen("\"first_child\":1,", "\"first_child\":0,", 1);
    assert_ne!(broken, text);
    assert!(BinaryVocabulary::from_reader(broken.as_bytes()).is_err());
    assert!(BinaryVocabulary::from_reader(&b"{}"[..]).is_err());
}

proptest::proptest! {
    #[test]
    fn l1_score_matches_the_dense_definition(
        a in proptest::collection::btree_map(0u32..50, 0.0f64..10.0, 0..20),
        b in proptest::collection::btree_map(0u32..50, 0.0f64..10.0, 0..20),
    ) {
        let va = BowVector::from_weights(a);
        let vb = BowVector::from_weights(b);
        let dense = |v: &BowVector| {
            let mut d = [0.0; 50];
            for &(w, x) in v.entries() {
                d[w as usize] = x;
            }
            d
        };
        let (da, db) = (dense(&va), dense(&vb));
        let l1: f64 = da.iter().zip(&db).map(|(x, y)| (x - y).abs()).sum();
        let s = va.score(&vb);
        proptest::prop_assert!((0.0..=1.0).contains(&s));
        proptest::prop_assert_eq!(s, vb.score(&va));
        if !va.is_empty() && !vb.is_empty() {
            proptest::prop_assert!((s - (1.0 - 0.5 * l1)).abs() < 1e-12);
        } else {
            proptest::prop_assert_eq!(s, 0.0);
        }
    }
}
