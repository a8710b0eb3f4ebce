//! The traversal stack of the wide BVHs' single-ray walks: the
//! pushed children and their entry distances in two arrays (structure of
//! arrays), so that a node's sorted children go onto it in two vector
//! stores ([`super::sort8`], as Embree's AVX-512 kernels push a sorted node;
//! Wald et al. 2014), with [`SLACK`] entries past the bound for those
//! stores.

use super::wide_node::Child4;
use std::mem::MaybeUninit;

/// Entries past a stack's bound that a vector push may write (a whole
/// node's eight, of which only the entered ones count).
pub(crate) const SLACK: usize = 8;

/// A stack of `N` entries plus [`SLACK`]; left uninitialised (zeroing it
/// cost about 5% of a ray's instructions, a memset per ray): only pushed
/// entries are read.
#[repr(C)]
pub(crate) struct Stack<const N: usize> {
    child: [MaybeUninit<Child4>; N],
    child_slack: [MaybeUninit<Child4>; SLACK],
    t: [MaybeUninit<f32>; N],
    t_slack: [MaybeUninit<f32>; SLACK],
}

impl<const N: usize> Stack<N> {
    /// An empty stack.
    #[inline(always)]
    pub fn new() -> Self {
        Stack {
            child: [const { MaybeUninit::uninit() }; N],
            child_slack: [const { MaybeUninit::uninit() }; SLACK],
            t: [const { MaybeUninit::uninit() }; N],
            t_slack: [const { MaybeUninit::uninit() }; SLACK],
        }
    }

    /// Raw access for the traversal loop: written and read through raw
    /// pointers, without bound checks (they and the copy of a sorted block
    /// cost about 4% of a ray's instructions, callgrind).
    #[inline(always)]
    pub fn ptr(&mut self) -> StackPtr {
        let base = self as *mut Self;
        // SAFETY: field addresses of a live value, formed from the pointer
        // to the whole stack, so that they may reach into the slack after
        // each array (`repr(C)`: `child_slack` follows `child`, `t_slack`
        // follows `t`, with no padding, the element types' sizes being
        // multiples of their alignment).
        unsafe {
            StackPtr {
                child: std::ptr::addr_of_mut!((*base).child) as *mut Child4,
                t: std::ptr::addr_of_mut!((*base).t) as *mut f32,
            }
        }
    }
}

/// Raw pointers into a [`Stack`]: entry `i` is `child[i]`, `t[i]`.
#[derive(Clone, Copy)]
pub(crate) struct StackPtr {
    pub child: *mut Child4,
    pub t: *mut f32,
}

impl StackPtr {
    /// Write entry `i`.
    ///
    /// # Safety
    /// `i` must be below the stack's `N + SLACK`.
    #[inline(always)]
    pub unsafe fn write(self, i: usize, c: Child4, t: f32) {
        // SAFETY: the caller's bound.
        unsafe {
            self.child.add(i).write(c);
            self.t.add(i).write(t);
        }
    }

    /// Read entry `i`.
    ///
    /// # Safety
    /// Entry `i` must have been written.
    #[inline(always)]
    pub unsafe fn read(self, i: usize) -> (Child4, f32) {
        // SAFETY: the caller's guarantee.
        unsafe { (self.child.add(i).read(), self.t.add(i).read()) }
    }
}
