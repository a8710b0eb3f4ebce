//! The choice of box kernel, made once per structure by run-time
//! detection (not per node): the 8-wide nodes of [`super::box8`] have an
//! AVX, an SSE and a scalar kernel, and the wide BVH's traversal is
//! compiled once for each feature set so that the kernel inlines into it.

/// The box kernel a structure uses, detected once when it is built
/// (run-time detection, not per node).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BoxPath {
    /// 256-bit AVX (with AVX2 and FMA present, as the traversal is compiled
    /// for them).
    Avx2,
    /// The AVX kernel, the traversal around it compiled for AVX-512 (F, VL, BW,
    /// DQ) besides: the same 256-bit arithmetic, bit for bit, with 32 vector
    /// registers and compares into mask registers, as Embree runs its AVX-512
    /// kernels on such CPUs (single incoherent rays 1.09x faster on the
    /// scatter).
    Avx512,
    /// Two 128-bit SSE halves.
    Sse,
    /// One box after the other (off x86_64; on it, only in tests).
    #[cfg_attr(target_arch = "x86_64", allow(dead_code))]
    Scalar,
}

impl BoxPath {
    /// The fastest kernel this CPU runs.
    pub fn detect() -> BoxPath {
        #[cfg(target_arch = "x86_64")]
        {
            if avx512() {
                BoxPath::Avx512
            } else if avx2() {
                BoxPath::Avx2
            } else {
                BoxPath::Sse
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            BoxPath::Scalar
        }
    }

    /// Every kernel this CPU runs (for tests).
    #[cfg(test)]
    pub fn available() -> Vec<BoxPath> {
        let mut v = vec![BoxPath::Scalar];
        #[cfg(target_arch = "x86_64")]
        {
            v.push(BoxPath::Sse);
            if avx2() {
                v.push(BoxPath::Avx2);
            }
            if avx512() {
                v.push(BoxPath::Avx512);
            } else {
                eprintln!("note: no AVX-512 on this CPU: the Avx512 traversal is not tested here");
            }
        }
        v
    }
}

/// AVX2 and FMA, which [`BoxPath::Avx2`]'s traversal is compiled for
/// (and the winding-number walk of `query/winding.rs`).
#[cfg(target_arch = "x86_64")]
pub(crate) fn avx2() -> bool {
    is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma")
}

/// Every feature [`BoxPath::Avx512`]'s traversal is compiled for (what its
/// `target_feature` attributes name).
#[cfg(target_arch = "x86_64")]
fn avx512() -> bool {
    avx2()
        && is_x86_feature_detected!("avx512f")
        && is_x86_feature_detected!("avx512vl")
        && is_x86_feature_detected!("avx512bw")
        && is_x86_feature_detected!("avx512dq")
        && is_x86_feature_detected!("bmi1")
        && is_x86_feature_detected!("bmi2")
        && is_x86_feature_detected!("lzcnt")
        && is_x86_feature_detected!("popcnt")
}
