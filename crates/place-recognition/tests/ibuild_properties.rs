//! Property tests of IBuILD's vocabulary search (Khan 2017, Fig. 4.9): the multi-index hashing
//! search returns exactly the index of the thesis' linear first-match scan, and whole IBuILD
//! runs give identical candidate lists with either engine.

use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use raypath_place_recognition::{
    Bits512, Candidate, Ibuild, IbuildConfig, PlaceRecognizer, VocabularySearch, WordIndex,
};

/// Fig. 4.9 written plainly: the first index within δ.
fn first_match(words: &[Bits512], q: &Bits512, delta: u32) -> Option<u32> {
    words
        .iter()
        .position(|w| w.hamming(q) < delta)
        .map(|j| j as u32)
}

/// A word: fresh random, or a near-duplicate of an earlier one (`H` around δ, both sides).
fn next_word(words: &[Bits512], delta: u32, rng: &mut ChaCha8Rng) -> Bits512 {
    if words.is_empty() || rng.random_bool(0.3) {
        Bits512::random(rng)
    } else {
        let base = words[rng.random_range(0..words.len())];
        base.with_flipped_bits(rng.random_range(0..=(delta as usize * 3 / 2 + 2)), rng)
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn multi_index_equals_linear_first_match(
        delta in 1u32..=200,
        seed in any::<u64>(),
        batches in 1usize..6,
    ) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut lin = WordIndex::new(delta, VocabularySearch::Linear).unwrap();
        let mut mih = WordIndex::new(delta, VocabularySearch::MultiIndex).unwrap();
        let mut auto = WordIndex::new(delta, VocabularySearch::Auto).unwrap();
        for _ in 0..batches {
            // Incremental appends, then queries against the grown vocabulary.
            for _ in 0..rng.random_range(1..80) {
                let w = next_word(lin.words(), delta, &mut rng);
                prop_assert_eq!(lin.push(w), mih.push(w));
                auto.push(w);
            }
            for _ in 0..40 {
                let q = next_word(lin.words(), delta, &mut rng);
                let want = first_match(lin.words(), &q, delta);
                prop_assert_eq!(lin.first_match(&q), want);
                prop_assert_eq!(mih.first_match(&q), want);
                prop_assert_eq!(auto.first_match(&q), want);
            }
        }
    }
}

/// Frames of a random walk through places (noisy copies of each place's descriptors), with
/// revisits.
fn frames(seed: u64) -> Vec<Vec<Bits512>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let places: Vec<Vec<Bits512>> = (0..6)
        .map(|_| (0..25).map(|_| Bits512::random(&mut rng)).collect())
        .collect();
    let mut out = Vec::new();
    for _ in 0..40 {
        let p = &places[rng.random_range(0..places.len())];
        for _ in 0..rng.random_range(1..4) {
            let noise = rng.random_range(0..30);
            let mut f: Vec<Bits512> = p
                .iter()
                .map(|w| w.with_flipped_bits(noise, &mut rng))
                .collect();
            f.extend((0..rng.random_range(0..6)).map(|_| Bits512::random(&mut rng)));
            out.push(f);
        }
    }
    out
}

fn run(
    config: IbuildConfig,
    frames: &[Vec<Bits512>],
) -> (Vec<Vec<Candidate>>, Vec<Vec<Candidate>>) {
    let mut m = Ibuild::new(config).expect("valid configuration");
    let mut online = Vec::new();
    for (t, f) in frames.iter().enumerate() {
        let d = m.describe_descriptors(f.clone());
        online.push(m.query(&d, t.saturating_sub(m.config().beta)));
        m.insert(d);
    }
    let kidnapped = (0..m.len()).map(|i| m.query_stored(i, m.len())).collect();
    (online, kidnapped)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(12))]

    #[test]
    fn candidate_lists_do_not_depend_on_the_search_engine(
        seed in any::<u64>(),
        delta in 20u32..140,
        recentroid in any::<bool>(),
        strict in any::<bool>(),
        fixed_point in any::<bool>(),
    ) {
        let frames = frames(seed);
        let config = |search| IbuildConfig {
            delta,
            search,
            recentroid_matched: recentroid,
            strict_majority: strict,
            merge_until_fixed_point: fixed_point,
            ..IbuildConfig::default()
        };
        let lin = run(config(VocabularySearch::Linear), &frames);
        let mih = run(config(VocabularySearch::MultiIndex), &frames);
        prop_assert_eq!(&lin, &mih);
        prop_assert_eq!(lin, run(config(VocabularySearch::Auto), &frames));
    }
}
