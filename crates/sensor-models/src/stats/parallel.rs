//! Parallel map building: rayon over chunks of scans or rays, per-thread partial maps.

use std::sync::Mutex;

use rayon::prelude::*;

use crate::dimension::Dimension;
use crate::stats::MappingConfig;
use crate::stats::insert::{StatsSink, insert_ray};

/// Inserts the rays of `items` into `target` in parallel.
///
/// Work is split into chunks of items that rayon schedules dynamically. A worker takes a
/// partial map from a pool (the target itself is the first one; `empty` makes more, at
/// most one per thread), inserts a chunk, and returns the partial to the pool; at the end
/// the partials are merged into one with `merge`. `placeholder` (a cheap, unusable value)
/// stands in `target` meanwhile. Because the statistics are integers
/// (see [`crate::CellStats`]) the result does not depend on the split or the thread count.
pub(crate) fn insert_parallel<D, S, T>(
    target: &mut S,
    placeholder: S,
    items: &[T],
    config: &MappingConfig,
    empty: impl Fn() -> S + Sync,
    merge: impl Fn(&mut S, S),
    rays_of: impl Fn(&T, &mut dyn FnMut(&D::Ray)) + Sync,
) where
    D: Dimension,
    S: StatsSink<D> + Send,
    T: Sync,
{
    if items.is_empty() {
        return;
    }
    let threads = rayon::current_num_threads().max(1);
    let chunk = items.len().div_ceil(threads * 16).max(1);
    let original = std::mem::replace(target, placeholder);
    let pool = Mutex::new(vec![original]);
    items.par_chunks(chunk).for_each(|chunk| {
        let taken = pool.lock().unwrap_or_else(|e| e.into_inner()).pop();
        let mut partial = taken.unwrap_or_else(&empty);
        for item in chunk {
            rays_of(item, &mut |ray| {
                insert_ray::<D, S>(&mut partial, ray, config)
            });
        }
        pool.lock().unwrap_or_else(|e| e.into_inner()).push(partial);
    });
    let mut partials = pool.into_inner().unwrap_or_else(|e| e.into_inner());
    let Some(mut result) = partials.pop() else {
        return;
    };
    for partial in partials {
        merge(&mut result, partial);
    }
    *target = result;
}
