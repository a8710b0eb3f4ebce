//! An array that is either owned or a private memory map of a file: the
//! leaf packs of a wide BVH loaded with `load_mapped` (`super::persist`)
//! are used where the file lies in the page cache, without a copy.

use super::words::Words;
use std::ops::{Deref, DerefMut};

/// The values of an array: an owned vector, or values mapped read-only
/// from a file, which become an owned copy when first written (a refit).
pub(crate) enum Store<W: Words> {
    /// Owned.
    Owned(Vec<W>),
    /// Mapped from a file.
    #[cfg(all(target_os = "linux", target_endian = "little"))]
    Mapped(Mapping<W>),
}

impl<W: Words> From<Vec<W>> for Store<W> {
    fn from(v: Vec<W>) -> Self {
        Store::Owned(v)
    }
}

impl<W: Words> Deref for Store<W> {
    type Target = [W];
    #[inline(always)]
    fn deref(&self) -> &[W] {
        match self {
            Store::Owned(v) => v,
            #[cfg(all(target_os = "linux", target_endian = "little"))]
            // SAFETY: `ptr` is aligned and `len` values lie in the mapping,
            // which lives as long as `self` (see `Mapping::new`).
            Store::Mapped(m) => unsafe { std::slice::from_raw_parts(m.ptr, m.len) },
        }
    }
}

impl<W: Words> DerefMut for Store<W> {
    /// The values, writable: a mapped array is copied first (mapped
    /// read-only, its pages are the page cache's own, with no copy until
    /// here).
    fn deref_mut(&mut self) -> &mut [W] {
        #[cfg(all(target_os = "linux", target_endian = "little"))]
        if let Store::Mapped(_) = self {
            *self = Store::Owned(self.to_vec());
        }
        match self {
            Store::Owned(v) => v,
            #[cfg(all(target_os = "linux", target_endian = "little"))]
            Store::Mapped(_) => unreachable!("copied above"),
        }
    }
}

/// `len` values of `W` mapped read-only and privately from a file.
#[cfg(all(target_os = "linux", target_endian = "little"))]
pub(crate) struct Mapping<W> {
    base: *mut libc::c_void,
    bytes: usize,
    ptr: *mut W,
    len: usize,
}

// SAFETY: the mapping is plain memory owned by the value, like a `Vec`.
#[cfg(all(target_os = "linux", target_endian = "little"))]
unsafe impl<W: Send> Send for Mapping<W> {}
// SAFETY: as above; the mapping is only read.
#[cfg(all(target_os = "linux", target_endian = "little"))]
unsafe impl<W: Sync> Sync for Mapping<W> {}

#[cfg(all(target_os = "linux", target_endian = "little"))]
impl<W: Words> Mapping<W> {
    /// Map `len` values at byte `offset` of `file` (a multiple of the
    /// values' alignment), read-only, the pages mapped ahead
    /// (`MAP_POPULATE`; a writable private mapping would be copied page by
    /// page by it).
    ///
    /// # Safety
    /// The file must not be truncated or written while the mapping lives
    /// (a shrunk file faults on access; a written one may change values).
    pub unsafe fn new(file: &std::fs::File, offset: u64, len: usize) -> std::io::Result<Self> {
        use std::os::fd::AsRawFd;
        // SAFETY: sysconf has no preconditions.
        let page = unsafe { libc::sysconf(libc::_SC_PAGESIZE) }.max(4096) as u64;
        let start = offset / page * page;
        let lead = (offset - start) as usize;
        let bytes = lead + len * std::mem::size_of::<W>();
        if len == 0 || !offset.is_multiple_of(std::mem::align_of::<W>() as u64) {
            return Err(std::io::Error::other("an empty or misaligned array"));
        }
        // SAFETY: a fresh private mapping of an open file; the kernel
        // checks the range against the file.
        let base = unsafe {
            libc::mmap(
                std::ptr::null_mut(),
                bytes,
                libc::PROT_READ,
                libc::MAP_PRIVATE | libc::MAP_POPULATE,
                file.as_raw_fd(),
                start as libc::off_t,
            )
        };
        if base == libc::MAP_FAILED {
            return Err(std::io::Error::last_os_error());
        }
        Ok(Mapping {
            base,
            bytes,
            // The base is page-aligned and `offset` a multiple of the
            // alignment, so the values are aligned.
            ptr: base.cast::<u8>().wrapping_add(lead).cast::<W>(),
            len,
        })
    }
}

#[cfg(all(target_os = "linux", target_endian = "little"))]
impl<W> Drop for Mapping<W> {
    fn drop(&mut self) {
        // SAFETY: the mapping made in `new`, unmapped once.
        unsafe {
            libc::munmap(self.base, self.bytes);
        }
    }
}
