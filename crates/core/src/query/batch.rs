//! One query answered for many inputs in parallel over the rayon pool: the
//! batch form shared by the point and multi-hit ray queries.

use crate::accel::BATCH_GRAIN;
use rayon::prelude::*;

/// `out[i] = answer(&inputs[i])` for every `i`, in parallel, in chunks of at
/// least [`BATCH_GRAIN`] so that cheap queries do not drown in scheduling.
pub(crate) fn answer_each<I: Sync, O: Send>(
    inputs: &[I],
    out: &mut [O],
    answer: impl Fn(&I) -> O + Sync,
) {
    assert_eq!(inputs.len(), out.len(), "one result per input");
    inputs
        .par_iter()
        .zip(out.par_iter_mut())
        .with_min_len(BATCH_GRAIN)
        .for_each(|(i, o)| *o = answer(i));
}
