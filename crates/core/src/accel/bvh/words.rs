//! Plain arrays of 32-bit words: what the saved file and the memory map
//! read and write as bytes.

/// A plain-data type made only of 32-bit words (`f32`, `u32`) with no
/// padding, so that its bytes may be read and written as such and every
/// bit pattern is a value.
///
/// # Safety
/// The type must be `repr(C)` (or transparent), hold only `f32` and `u32`
/// fields (directly or in arrays and such types), and have no padding.
pub unsafe trait Words: Copy + Send + Sync + 'static {}

// SAFETY: a `u32` is one word.
unsafe impl Words for u32 {}

/// The bytes of `v`, in the host's byte order.
pub(crate) fn bytes_of<W: Words>(v: &[W]) -> &[u8] {
    // SAFETY: `Words` types have no padding, so every byte is initialised.
    unsafe { std::slice::from_raw_parts(v.as_ptr().cast::<u8>(), std::mem::size_of_val(v)) }
}

/// The bytes of `v`, writable.
pub(crate) fn bytes_of_mut<W: Words>(v: &mut [W]) -> &mut [u8] {
    // SAFETY: as `bytes_of`; every bit pattern is a `Words` value.
    unsafe { std::slice::from_raw_parts_mut(v.as_mut_ptr().cast::<u8>(), std::mem::size_of_val(v)) }
}
