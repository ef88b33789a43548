//! The binary vocabulary tree of Gálvez-López & Tardós (T-RO 2012): hierarchical k-medians
//! ("k-majority") clustering of binary descriptors with k-means++ seeding by Hamming distance;
//! the leaves are the words, weighted by their inverse document frequency.

use std::fmt;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::{Bits512, PlaceError, Result};

use super::bow::{BowVector, DirectIndex};

/// Below this many descriptors a node's assignment step runs on one thread (ours).
const PARALLEL_ASSIGN_MIN: usize = 8192;

/// Parameters of vocabulary training.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct VocabularyConfig {
    /// Branching factor `k_w`: children per node. Default 10 (Gálvez-López & Tardós 2012).
    pub branching: usize,
    /// Depth `L_w`: levels below the root, so at most `k_w^L_w` words. Default 6 (Gálvez-López
    /// & Tardós 2012; 5 is the usual lighter choice).
    pub depth: usize,
    /// Assignment/update rounds of k-medians per node (stops earlier when the assignment no
    /// longer changes). Default 10 (ours; the paper does not give a number).
    pub iterations: usize,
}

impl Default for VocabularyConfig {
    fn default() -> Self {
        Self {
            branching: 10,
            depth: 6,
            iterations: 10,
        }
    }
}

impl VocabularyConfig {
    fn validate(&self) -> Result<()> {
        let bad = |name, reason: &str| {
            Err(PlaceError::InvalidParameter {
                name,
                reason: reason.to_string(),
            })
        };
        if self.branching < 2 {
            return bad("branching", "must be at least 2");
        }
        if self.depth == 0 || self.depth > 16 {
            return bad("depth", "must be between 1 and 16");
        }
        if self.iterations == 0 {
            return bad("iterations", "must be at least 1");
        }
        Ok(())
    }
}

/// One tree node; children of a node are contiguous and the nodes are stored breadth-first.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct Node {
    /// Cluster centre (bitwise majority of the training descriptors; zeros for the root).
    centre: Bits512,
    /// Index of the first child (meaningless for leaves).
    first_child: u32,
    /// Number of children; 0 for a leaf (a word).
    child_count: u32,
    /// The word of a leaf (`u32::MAX` for inner nodes).
    word: u32,
}

/// A trained binary vocabulary tree: branching `k_w`, depth ≤ `L_w`, leaves are words with an
/// idf weight `log(N / n_i)` (Gálvez-López & Tardós 2012).
///
/// Train once on other sequences ([`BinaryVocabulary::train`]), save with
/// [`to_writer`](BinaryVocabulary::to_writer) (JSON) and reuse with
/// [`from_reader`](BinaryVocabulary::from_reader). Deserialisation checks the tree structure.
#[derive(Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "VocabularyData")]
pub struct BinaryVocabulary {
    branching: usize,
    depth: usize,
    /// `N`, the number of training images.
    training_images: u64,
    nodes: Vec<Node>,
    /// `n_i`, the number of training images with a descriptor in word `i`.
    image_counts: Vec<u64>,
    /// The idf weight `ln(N / n_i)` of each word, computed from the counts.
    #[serde(skip)]
    weights: Vec<f64>,
}

/// The serialised form, checked by `TryFrom` before it becomes a [`BinaryVocabulary`].
#[derive(Deserialize)]
struct VocabularyData {
    branching: usize,
    depth: usize,
    training_images: u64,
    nodes: Vec<Node>,
    image_counts: Vec<u64>,
}

impl fmt::Debug for BinaryVocabulary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("BinaryVocabulary")
            .field("branching", &self.branching)
            .field("depth", &self.depth)
            .field("nodes", &self.nodes.len())
            .field("words", &self.weights.len())
            .finish()
    }
}

impl TryFrom<VocabularyData> for BinaryVocabulary {
    type Error = PlaceError;

    fn try_from(data: VocabularyData) -> Result<Self> {
        let bad = |reason: String| Err(PlaceError::BadInput(format!("vocabulary: {reason}")));
        let VocabularyData {
            branching,
            depth,
            training_images,
            nodes,
            image_counts,
        } = data;
        if nodes.is_empty() {
            return bad("no nodes".into());
        }
        // Breadth-first layout: children ranges follow each other in parent order, after
        // their parent; leaves are numbered 0, 1, … in node order.
        let mut next_child = 1usize;
        let mut next_word = 0usize;
        for (i, node) in nodes.iter().enumerate() {
            if node.child_count == 0 {
                if node.word as usize != next_word {
                    return bad(format!(
                        "leaf {i} has word {}, expected {next_word}",
                        node.word
                    ));
                }
                next_word += 1;
            } else {
                let first = node.first_child as usize;
                if first != next_child || first <= i || node.child_count as usize > branching {
                    return bad(format!("node {i} has bad children"));
                }
                next_child += node.child_count as usize;
            }
        }
        if next_child != nodes.len() {
            return bad(format!(
                "{} nodes, children cover {next_child}",
                nodes.len()
            ));
        }
        if next_word != image_counts.len() {
            return bad(format!(
                "{next_word} leaves but {} image counts",
                image_counts.len()
            ));
        }
        if let Some(n) = image_counts
            .iter()
            .find(|&&n| n == 0 || n > training_images)
        {
            return bad(format!(
                "image count {n} outside 1..={training_images} training images"
            ));
        }
        Ok(Self::assemble(
            branching,
            depth,
            training_images,
            nodes,
            image_counts,
        ))
    }
}

impl BinaryVocabulary {
    /// Trains the tree on descriptors grouped per training image (`images[j]` are the
    /// descriptors of image `j`; `N = images.len()` in the idf).
    ///
    /// From the root, each node holding more than `k_w` descriptors is clustered into at most
    /// `k_w` children by k-medians with k-means++ seeding (Hamming distance, probability ∝ D²),
    /// the centre being the bitwise majority of eq. (4.1); nodes with ≤ `k_w` descriptors, or
    /// whose descriptors are all equal, stay leaves. Leaves down to level `L_w` are the words,
    /// weighted `idf_i = ln(N / n_i)` with `n_i` the number of training images with a
    /// descriptor in word `i`. Each node draws from its own ChaCha8 stream derived from `seed`
    /// and the node index, so the result does not depend on the number of threads.
    pub fn train(images: &[Vec<Bits512>], config: &VocabularyConfig, seed: u64) -> Result<Self> {
        Self::train_with_words(images, config, seed).map(|(vocabulary, _)| vocabulary)
    }

    /// [`train`](BinaryVocabulary::train), also returning the word (leaf) holding each
    /// training descriptor, in flattened input order.
    pub(super) fn train_with_words(
        images: &[Vec<Bits512>],
        config: &VocabularyConfig,
        seed: u64,
    ) -> Result<(Self, Vec<u32>)> {
        config.validate()?;
        let descriptors: Vec<Bits512> = images.iter().flatten().copied().collect();
        if descriptors.is_empty() {
            return Err(PlaceError::BadInput(
                "vocabulary training: no descriptors".into(),
            ));
        }
        let image_of: Vec<u32> = images
            .iter()
            .enumerate()
            .flat_map(|(j, d)| std::iter::repeat_n(j as u32, d.len()))
            .collect();
        let mut nodes = vec![Node {
            centre: Bits512::zeros(),
            first_child: 0,
            child_count: 0,
            word: u32::MAX,
        }];
        let mut frontier: Vec<(usize, Vec<u32>)> =
            vec![(0, (0..descriptors.len() as u32).collect())];
        let mut leaves: Vec<(usize, Vec<u32>)> = Vec::new();
        for _ in 0..config.depth {
            let splits: Vec<Vec<(Bits512, Vec<u32>)>> = frontier
                .par_iter()
                .map(|(id, members)| {
                    if members.len() <= config.branching {
                        return Vec::new();
                    }
                    let mut rng = ChaCha8Rng::seed_from_u64(seed);
                    rng.set_stream(*id as u64);
                    k_medians(&descriptors, members, config, &mut rng)
                })
                .collect();
            let mut next = Vec::new();
            for ((id, members), clusters) in frontier.into_iter().zip(splits) {
                if clusters.len() < 2 {
                    leaves.push((id, members));
                    continue;
                }
                nodes[id].first_child = nodes.len() as u32;
                nodes[id].child_count = clusters.len() as u32;
                for (centre, child_members) in clusters {
                    next.push((nodes.len(), child_members));
                    nodes.push(Node {
                        centre,
                        first_child: 0,
                        child_count: 0,
                        word: u32::MAX,
                    });
                }
            }
            frontier = next;
        }
        leaves.extend(frontier);
        leaves.sort_unstable_by_key(|(id, _)| *id);
        let mut image_counts = Vec::with_capacity(leaves.len());
        let mut word_of = vec![0u32; descriptors.len()];
        for (word, (id, members)) in leaves.iter().enumerate() {
            nodes[*id].word = word as u32;
            for &m in members {
                word_of[m as usize] = word as u32;
            }
            // Members are in increasing descriptor order, so their images are sorted.
            let mut n_i = 0u64;
            let mut last = u32::MAX;
            for &m in members {
                if image_of[m as usize] != last {
                    last = image_of[m as usize];
                    n_i += 1;
                }
            }
            image_counts.push(n_i);
        }
        let vocabulary = Self::assemble(
            config.branching,
            config.depth,
            images.len() as u64,
            nodes,
            image_counts,
        );
        Ok((vocabulary, word_of))
    }

    /// The vocabulary with its idf weights computed from the image counts.
    fn assemble(
        branching: usize,
        depth: usize,
        training_images: u64,
        nodes: Vec<Node>,
        image_counts: Vec<u64>,
    ) -> Self {
        let n = training_images as f64;
        let weights = image_counts
            .iter()
            .map(|&n_i| (n / n_i as f64).ln()) // idf_i = log(N / n_i)
            .collect();
        Self {
            branching,
            depth,
            training_images,
            nodes,
            image_counts,
            weights,
        }
    }

    /// Branching factor `k_w` the tree was trained with.
    pub fn branching(&self) -> usize {
        self.branching
    }

    /// Maximum depth `L_w` the tree was trained with.
    pub fn depth(&self) -> usize {
        self.depth
    }

    /// Number of words (leaves).
    pub fn word_count(&self) -> usize {
        self.weights.len()
    }

    /// Number of tree nodes, root included.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// The idf weight `ln(N / n_i)` of a word (`None` when out of range).
    pub fn idf(&self, word: u32) -> Option<f64> {
        self.weights.get(word as usize).copied()
    }

    /// The word of a descriptor and its node at tree level `level` (root = 0; the leaf itself
    /// when the path ends above that level): descends from the root to the child at the
    /// smallest Hamming distance (first child on ties).
    pub fn descend(&self, descriptor: &Bits512, level: usize) -> (u32, u32) {
        let mut id = 0usize;
        let mut at_level = 0u32;
        let mut depth = 0usize;
        loop {
            if depth == level {
                at_level = id as u32;
            }
            let node = &self.nodes[id];
            if node.child_count == 0 {
                if depth < level {
                    at_level = id as u32;
                }
                return (node.word, at_level);
            }
            let first = node.first_child as usize;
            let children = &self.nodes[first..first + node.child_count as usize];
            let mut best = (u32::MAX, 0usize);
            for (c, child) in children.iter().enumerate() {
                let d = descriptor.hamming(&child.centre);
                if d < best.0 {
                    best = (d, c);
                }
            }
            id = first + best.1;
            depth += 1;
        }
    }

    /// The word of a descriptor (see [`descend`](BinaryVocabulary::descend)).
    pub fn word(&self, descriptor: &Bits512) -> u32 {
        self.descend(descriptor, 0).0
    }

    /// The bag-of-words vector of an image's descriptors and its direct-index entry (node at
    /// tree level `direct_index_level` → indices of the descriptors under it).
    ///
    /// Entry `i` is `tf_i · idf_i` with `tf_i = n_{i,I} / n_I` (occurrences of word `i` over
    /// the number of descriptors), L1-normalised; words of zero weight are left out, so an
    /// image without descriptors, or only with words seen in every training image, gives the
    /// empty vector.
    pub fn transform(
        &self,
        descriptors: &[Bits512],
        direct_index_level: usize,
    ) -> (BowVector, DirectIndex) {
        let mut words = Vec::with_capacity(descriptors.len());
        let mut nodes = Vec::with_capacity(descriptors.len());
        for (j, d) in descriptors.iter().enumerate() {
            let (word, node) = self.descend(d, direct_index_level);
            words.push(word);
            nodes.push((node, j as u32));
        }
        words.sort_unstable();
        let mut counts: Vec<(u32, f64)> = Vec::new();
        for w in words {
            match counts.last_mut() {
                Some((last, c)) if *last == w => *c += 1.0,
                _ => counts.push((w, 1.0)),
            }
        }
        // tf-idf; the common factor 1 / n_I of tf cancels in the L1 normalisation.
        let weighted = counts
            .into_iter()
            .map(|(w, c)| (w, c * self.weights[w as usize]));
        (
            BowVector::from_weights(weighted),
            DirectIndex::from_pairs(nodes),
        )
    }

    /// Writes the vocabulary as JSON.
    pub fn to_writer(&self, writer: impl std::io::Write) -> std::io::Result<()> {
        serde_json::to_writer(writer, self).map_err(std::io::Error::from)
    }

    /// Reads a vocabulary written by [`to_writer`](BinaryVocabulary::to_writer), checking its
    /// structure.
    pub fn from_reader(reader: impl std::io::Read) -> Result<Self> {
        serde_json::from_reader(std::io::BufReader::new(reader))
            .map_err(|e| PlaceError::BadInput(format!("vocabulary: {e}")))
    }
}

/// Index of the nearest centre (first on ties).
#[inline]
fn nearest(d: &Bits512, centres: &[Bits512]) -> u32 {
    let mut best = (u32::MAX, 0u32);
    for (c, centre) in centres.iter().enumerate() {
        let h = d.hamming(centre);
        if h < best.0 {
            best = (h, c as u32);
        }
    }
    best.1
}

/// Nearest-centre assignment of the members (parallel for large nodes; pure per member).
fn assign(descriptors: &[Bits512], members: &[u32], centres: &[Bits512]) -> Vec<u32> {
    let one = |&m: &u32| nearest(&descriptors[m as usize], centres);
    if members.len() >= PARALLEL_ASSIGN_MIN {
        members.par_iter().map(one).collect()
    } else {
        members.iter().map(one).collect()
    }
}

/// Members grouped by their assigned cluster, in increasing member order.
fn groups(members: &[u32], assignment: &[u32], k: usize) -> Vec<Vec<u32>> {
    let mut out = vec![Vec::new(); k];
    for (&m, &a) in members.iter().zip(assignment) {
        out[a as usize].push(m);
    }
    out
}

/// k-means++ seeding: the first centre uniformly, each next one with probability ∝ D², D the
/// Hamming distance to the nearest chosen centre. Stops early when every member coincides with
/// a centre.
fn seed_centres(
    descriptors: &[Bits512],
    members: &[u32],
    k: usize,
    rng: &mut ChaCha8Rng,
) -> Vec<Bits512> {
    let first = descriptors[members[rng.random_range(0..members.len())] as usize];
    let mut centres = vec![first];
    let mut d2: Vec<u64> = members
        .iter()
        .map(|&m| u64::from(descriptors[m as usize].hamming(&first)).pow(2))
        .collect();
    while centres.len() < k {
        let total: u64 = d2.iter().sum();
        if total == 0 {
            break;
        }
        let r = rng.random_range(0..total);
        let mut acc = 0u64;
        let mut pick = 0usize;
        for (i, &w) in d2.iter().enumerate() {
            acc += w;
            if acc > r {
                pick = i;
                break;
            }
        }
        let centre = descriptors[members[pick] as usize];
        centres.push(centre);
        for (w, &m) in d2.iter_mut().zip(members) {
            *w = (*w).min(u64::from(descriptors[m as usize].hamming(&centre)).pow(2));
        }
    }
    centres
}

/// k-medians of one node: seeding, then rounds of majority update and reassignment. The
/// returned clusters are non-empty and each holds exactly the members whose nearest centre it
/// is, so a training descriptor descends to the leaf holding it.
fn k_medians(
    descriptors: &[Bits512],
    members: &[u32],
    config: &VocabularyConfig,
    rng: &mut ChaCha8Rng,
) -> Vec<(Bits512, Vec<u32>)> {
    let mut centres = seed_centres(descriptors, members, config.branching, rng);
    let k = centres.len();
    let mut assignment = assign(descriptors, members, &centres);
    for _ in 0..config.iterations {
        let grouped = groups(members, &assignment, k);
        for (centre, group) in centres.iter_mut().zip(&grouped) {
            // Eq. (4.1): bitwise majority; an emptied cluster keeps its centre.
            if let Some(c) = Bits512::centroid(group.iter().map(|&m| &descriptors[m as usize])) {
                *centre = c;
            }
        }
        let next = assign(descriptors, members, &centres);
        if next == assignment {
            break;
        }
        assignment = next;
    }
    centres
        .into_iter()
        .zip(groups(members, &assignment, k))
        .filter(|(_, g)| !g.is_empty())
        .collect()
}
