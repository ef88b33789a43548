//! Unit tests of the IBuILD pipeline on hand-made descriptors.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::*;

fn ibuild(search: VocabularySearch) -> Ibuild {
    Ibuild::new(IbuildConfig {
        search,
        ..IbuildConfig::default()
    })
    .unwrap()
}

/// Random words are ~256 bits apart: nothing matches at δ = 80.
struct Words {
    a: Bits512,
    b: Bits512,
    c: Bits512,
    h: Bits512,
    d: Bits512,
    e: Bits512,
    f: Bits512,
    g: Bits512,
}

fn words() -> Words {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let mut w = || Bits512::random(&mut rng);
    Words {
        a: w(),
        b: w(),
        c: w(),
        h: w(),
        d: w(),
        e: w(),
        f: w(),
        g: w(),
    }
}

/// Images {A, B, C, H}, {A, D}, {B, E}.
fn three_images(search: VocabularySearch) -> (Ibuild, Words) {
    let w = words();
    let mut m = ibuild(search);
    m.insert(IbuildDescription::from_words(vec![w.a, w.b, w.c, w.h]));
    m.insert(IbuildDescription::from_words(vec![w.a, w.d]));
    m.insert(IbuildDescription::from_words(vec![w.b, w.e]));
    (m, w)
}

#[test]
fn frequencies_and_inverted_index_follow_updates() {
    let (mut m, w) = three_images(VocabularySearch::MultiIndex);
    let v = m.vocabulary();
    assert_eq!(v.len(), 6);
    assert_eq!(v.frequencies(), &[2, 2, 1, 1, 1, 1]);
    assert_eq!(v.images_with(0), &[0, 1]);
    assert_eq!(v.images_with(1), &[0, 2]);
    assert_eq!(v.words_of(0), &[0, 1, 2, 3]);
    assert_eq!(v.words_of(1), &[0, 4]);
    assert_eq!(v.words_of(2), &[1, 5]);
    // Two words of one image finding the same old word count once; new words start at 1.
    let mut near_a = w.a;
    near_a.set_bit(0, !near_a.bit(0));
    m.insert(IbuildDescription::from_words(vec![w.a, near_a, w.f]));
    let v = m.vocabulary();
    assert_eq!(v.frequencies(), &[3, 2, 1, 1, 1, 1, 1]);
    assert_eq!(v.images_with(0), &[0, 1, 3]);
    assert_eq!(v.words_of(3), &[0, 6]);
    assert_eq!(
        v.words()[0],
        w.a,
        "matched words are not re-centroided by default"
    );
    assert_eq!(m.len(), 4);
}

#[test]
fn recentroid_flag_updates_matched_words() {
    let w = words();
    let mut m = Ibuild::new(IbuildConfig {
        recentroid_matched: true,
        ..IbuildConfig::default()
    })
    .unwrap();
    m.insert(IbuildDescription::from_words(vec![w.a]));
    let mut near_a = w.a;
    near_a.set_bit(5, !near_a.bit(5));
    m.insert(IbuildDescription::from_words(vec![near_a]));
    assert_eq!(m.vocabulary().words(), &[w.a.pair_centroid(&near_a)]);
}

#[test]
fn similarity_is_the_modified_jaccard_index_as_printed() {
    for search in [VocabularySearch::Linear, VocabularySearch::MultiIndex] {
        let (m, w) = three_images(search);
        // Query {A, B, F, G}: old words A (f = 2), B (f = 2); N_new = 2.
        let d = IbuildDescription::from_words(vec![w.a, w.b, w.f, w.g]);
        let c = m.query(&d, 3);
        // I_0: U = {A, B}: (1/2 + 1/2)·2 = 2; T = {C, H}: (1 + 1)·2 = 4 → S = 2/(2 + 4 + 2).
        // I_1: U = {A}: 1/2·1; T = {D}: 1·1 → S = 0.5/(0.5 + 1 + 2) = 1/7; I_2 likewise.
        let s = [0.25, 1.0 / 7.0, 1.0 / 7.0];
        let total: f64 = s.iter().sum();
        assert_eq!(c.len(), 3);
        for (k, cand) in c.iter().enumerate() {
            assert_eq!(cand.frame, k);
            assert!(
                (cand.score - s[k] / total).abs() < 1e-12,
                "{search:?} {cand:?}"
            );
        }
        assert!((c[0].score - 7.0 / 15.0).abs() < 1e-12);
    }
}

#[test]
fn symmetric_score_penalises_subsets_and_is_not_normalised() {
    let w = words();
    let mut m = Ibuild::new(IbuildConfig {
        score: IbuildScore::Symmetric,
        ..IbuildConfig::default()
    })
    .unwrap();
    m.insert(IbuildDescription::from_words(vec![w.a, w.b, w.c, w.h]));
    m.insert(IbuildDescription::from_words(vec![w.a, w.d]));
    m.insert(IbuildDescription::from_words(vec![w.b, w.e]));
    // Query {A, B, F, G} as above: old A, B (f = 2), N_new = 2.
    let d = IbuildDescription::from_words(vec![w.a, w.b, w.f, w.g]);
    let c = m.query(&d, 3);
    // I_0: Q = ∅, so S = 2/(2 + 4 + 2) = 1/4 unchanged.
    // I_1: U = {A}: 1/2; T = {D}: 1; Q = {B}: 1/2·1 → S = 0.5/(0.5 + 1 + 0.5 + 2) = 1/8.
    let s = [0.25, 0.125, 0.125];
    for (k, cand) in c.iter().enumerate() {
        assert!((cand.score - s[k]).abs() < 1e-12, "{cand:?}");
    }
    // Kidnapped: image 1 ({A, D}) against itself scores 1; the printed score gives image 0's
    // superset the same kind of tie for a subset query, the symmetric one does not.
    let stored = m.query_stored(1, 3);
    let own = stored.iter().find(|c| c.frame == 1).unwrap();
    assert!((own.score - 1.0).abs() < 1e-12);
    assert!(
        stored
            .iter()
            .filter(|c| c.frame != 1)
            .all(|c| c.score < 1.0)
    );
}

#[test]
fn no_candidate_from_a_single_hypothesis() {
    let (m, w) = three_images(VocabularySearch::MultiIndex);
    let d = IbuildDescription::from_words(vec![w.a, w.b, w.f]);
    assert!(m.query(&d, 0).is_empty());
    assert!(m.query(&d, 1).is_empty(), "only I_0 before 1: |L| = 1");
    assert_eq!(m.query(&d, 2).len(), 2);
    // C only occurs in I_0: |L| = 1 at any `before`.
    let only_c = IbuildDescription::from_words(vec![w.c, w.g]);
    assert!(m.query(&only_c, 3).is_empty());
    // Nothing old at all.
    assert!(
        m.query(&IbuildDescription::from_words(vec![w.g]), 3)
            .is_empty()
    );
}

#[test]
fn cached_assignment_is_refreshed_after_an_update() {
    let w = words();
    let mut m = ibuild(VocabularySearch::MultiIndex);
    m.insert(IbuildDescription::from_words(vec![w.a, w.b]));
    m.insert(IbuildDescription::from_words(vec![w.a, w.c]));
    // Described against a vocabulary without D; D then appears in two images.
    m.reset_tracking();
    let stale = m.describe_descriptors(vec![w.d, w.c]);
    m.insert(IbuildDescription::from_words(vec![w.d]));
    m.insert(IbuildDescription::from_words(vec![w.d, w.e]));
    let fresh = IbuildDescription::from_words(stale.words().to_vec());
    assert_eq!(m.query(&stale, 4), m.query(&fresh, 4));
    assert_eq!(m.query(&stale, 4).len(), 3);
}

/// A sequence of places; each place is seen in `per_place` frames, each frame a noisy copy of
/// the place's descriptors (plus some clutter).
fn sequence(places: usize, per_place: usize, seed: u64) -> Vec<Vec<Bits512>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let pools: Vec<Vec<Bits512>> = (0..places)
        .map(|_| (0..30).map(|_| Bits512::random(&mut rng)).collect())
        .collect();
    let mut frames = Vec::new();
    for pool in &pools {
        for _ in 0..per_place {
            let mut f: Vec<Bits512> = pool
                .iter()
                .map(|w| w.with_flipped_bits(10, &mut rng))
                .collect();
            f.extend((0..5).map(|_| Bits512::random(&mut rng)));
            frames.push(f);
        }
    }
    frames
}

#[test]
fn kidnapped_mode_retrieves_every_frame_itself_first() {
    let mut m = ibuild(VocabularySearch::MultiIndex);
    let frames = sequence(6, 3, 5);
    for f in &frames {
        let d = m.describe_descriptors(f.clone());
        m.insert(d);
    }
    let n = m.len();
    let mut with_words = 0;
    for i in 0..n {
        let c = m.query_stored(i, n);
        if m.vocabulary().words_of(i).is_empty() {
            assert!(c.is_empty());
            continue;
        }
        with_words += 1;
        let own = c
            .iter()
            .find(|c| c.frame == i)
            .expect("a frame is its own hypothesis");
        // S = 1 against itself, the largest value; a frame whose words are a subset of
        // frame i's also scores 1 (T = ∅), hence ≥ rather than >.
        for other in c.iter().filter(|c| c.frame != i) {
            assert!(own.score >= other.score, "frame {i}: {own:?} vs {other:?}");
        }
        // Frames of one place share their words; frames tied with i are of i's place.
        for o in c.iter().filter(|o| o.score >= own.score) {
            assert_eq!(o.frame / 3, i / 3, "frame {i}: {o:?}");
        }
    }
    // Place changes leave frames without tracked features; the others have words.
    assert!(with_words >= 12, "{with_words}");
    let t = m.stage_times();
    assert_eq!((t.described, t.inserted, t.queries), (18, 18, 18));
}

#[test]
fn online_revisit_is_proposed_and_search_engines_agree() {
    let frames = sequence(5, 4, 9);
    let mut order: Vec<usize> = (0..frames.len()).collect();
    order.extend(0..4); // revisit place 0
    let run = |search: VocabularySearch| {
        let mut m = ibuild(search);
        let mut out = Vec::new();
        for (t, &k) in order.iter().enumerate() {
            let d = m.describe_descriptors(frames[k].clone());
            out.push(m.query(&d, t.saturating_sub(m.config().beta)));
            m.insert(d);
        }
        out
    };
    let lin = run(VocabularySearch::Linear);
    assert_eq!(lin, run(VocabularySearch::MultiIndex));
    assert_eq!(lin, run(VocabularySearch::Auto));
    // The last revisit frames propose place 0 (frames 0–3) as best.
    for c in &lin[order.len() - 2..] {
        let best = c.iter().max_by(|a, b| a.score.total_cmp(&b.score)).unwrap();
        assert!(best.frame < 4, "{best:?}");
    }
}

#[test]
fn config_is_validated() {
    for delta in [0, 513] {
        let c = IbuildConfig {
            delta,
            ..IbuildConfig::default()
        };
        assert!(Ibuild::new(c).is_err());
    }
    let c = IbuildConfig {
        beta: 0,
        ..IbuildConfig::default()
    };
    assert!(Ibuild::new(c).is_err());
    assert!(Ibuild::new(IbuildConfig::default()).is_ok());
    assert_eq!(ibuild(VocabularySearch::Linear).name(), "ibuild");
}
