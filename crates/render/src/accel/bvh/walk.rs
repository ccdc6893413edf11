//! The walks of a [`Bvh`] for a prepared ray: closest hit and any hit, each
//! as a head (an empty tree, the root's box, a root whose children are all
//! leaves) and a stack walk for deeper trees.
//!
//! The `*_prepared` forms inline both parts into their caller (a mesh's own
//! traversal, where the deep walk is the common case). The top level of a
//! scene inlines the head only (`*_split`) and runs the stack walk
//! (`*_walk`) in a function of its own: in a small scene (a Cornell box) every query ends in
//! the head, and the stack walk's frame (several kilobytes of stack, probed
//! page by page at every call) and its register pressure, which would make
//! the head keep its per-ray constants on the stack, stay out of that path.
//! The same steps in the same order either way, so the same hits.

use std::mem::MaybeUninit;

use super::node::{leaf_range, NodeTest, RayPre, EMPTY, LEAF};
use super::{AnyLeaf, Bvh, ClosestLeaf, Traversal, STACK, WIDTH};

impl Bvh {
    /// [`Bvh::closest`] for a ray already prepared (see [`Traversal`]).
    #[inline(always)]
    pub(crate) fn closest_prepared<L: ClosestLeaf>(&self, tr: &Traversal, t_max: f32, mut leaf: L) -> bool {
        let test = tr.test();
        if let Some(hit) = self.closest_head(&tr.r, &test, t_max, &mut leaf) {
            return hit;
        }
        self.closest_stack(&tr.r, &test, t_max, &mut leaf)
    }

    /// The head of the closest-hit walk of a ray prepared as `tr`, for a
    /// caller that runs [`Bvh::closest_walk`] out of line when it returns
    /// `None` (see the module documentation).
    #[inline(always)]
    pub(crate) fn closest_split<L: ClosestLeaf>(
        &self,
        tr: &Traversal,
        t_max: f32,
        leaf: &mut L,
    ) -> Option<bool> {
        self.closest_head(&tr.r, &tr.test(), t_max, leaf)
    }

    /// The rest of the walk after [`Bvh::closest_split`] returned `None`.
    #[inline(always)]
    pub(crate) fn closest_walk<L: ClosestLeaf>(&self, tr: &Traversal, t_max: f32, leaf: &mut L) -> bool {
        self.closest_stack(&tr.r, &tr.test(), t_max, leaf)
    }

    /// The closest-hit walk's answer when the tree is empty, the ray misses
    /// a one-leaf tree's box, or the root is the only node; `None` when the
    /// stack walk must run.
    #[inline(always)]
    fn closest_head<L: ClosestLeaf>(
        &self,
        r: &RayPre,
        test: &NodeTest,
        mut t_max: f32,
        leaf: &mut L,
    ) -> Option<bool> {
        let cur = self.root;
        if cur & LEAF != 0 && (cur == EMPTY || !r.hit_box(&self.bounds, t_max)) {
            return Some(false);
        }
        let root = self.signed_root.as_deref()?;
        // One node whose children are all leaves (the top level of a small
        // scene): its hit leaves nearest first, the order the stack walk
        // would give (equal distances: the higher slot first), without the
        // stack or the sort.
        let (tn, mut mask) = test.hit_root(r, &self.nodes, root, t_max);
        let mut hit = false;
        while mask != 0 {
            let mut k = mask.trailing_zeros() as usize;
            let mut m = mask & (mask - 1);
            while m != 0 {
                let i = m.trailing_zeros() as usize;
                m &= m - 1;
                if tn[i] <= tn[k] {
                    k = i;
                }
            }
            mask &= !(1 << k);
            let c = root.child[k];
            if tn[k] <= t_max && c != EMPTY {
                hit |= leaf.test(leaf_range(c), &mut t_max);
            }
        }
        Some(hit)
    }

    /// The closest-hit walk from the root with a stack of deferred
    /// children, nearest first.
    #[inline(always)]
    fn closest_stack<L: ClosestLeaf>(
        &self,
        r: &RayPre,
        test: &NodeTest,
        mut t_max: f32,
        leaf: &mut L,
    ) -> bool {
        let nodes = &self.nodes[..];
        let mut cur = self.root;
        // Entries: child reference in the low half, entry distance's bits in
        // the high half. Only entries below `sp` are ever read.
        let mut stack = [MaybeUninit::<u64>::uninit(); STACK];
        let mut sp = 0;
        macro_rules! push {
            ($t:expr, $c:expr) => {{
                stack[sp] = MaybeUninit::new(($t.to_bits() as u64) << 32 | $c as u64);
                sp += 1;
            }};
        }
        let mut hit = false;
        loop {
            if cur & LEAF != 0 {
                // An unused slot is never a leaf, even if the box test let it
                // through (a NaN ray passes every comparison as a hit).
                if cur != EMPTY {
                    hit |= leaf.test(leaf_range(cur), &mut t_max);
                }
            } else {
                let n = &nodes[cur as usize];
                let (tn, mut mask) = test.hit(r, n, t_max);
                if mask != 0 {
                    let a = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    if mask == 0 {
                        cur = n.child[a];
                        continue;
                    }
                    let b = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    if mask == 0 {
                        // The common case past the top levels: defer the
                        // farther of two.
                        let (near, far) = if tn[b] <= tn[a] { (b, a) } else { (a, b) };
                        push!(tn[far], n.child[far]);
                        cur = n.child[near];
                        continue;
                    }
                    // Three or more: sort by entry distance, push all but the
                    // nearest (farthest first), descend into the nearest.
                    let mut k = [(0.0f32, 0u32); WIDTH];
                    k[0] = (tn[a], n.child[a]);
                    let mut len = 1;
                    let mut m = mask | 1 << b;
                    while m != 0 {
                        let i = m.trailing_zeros() as usize;
                        m &= m - 1;
                        let mut j = len;
                        while j > 0 && k[j - 1].0 < tn[i] {
                            k[j] = k[j - 1];
                            j -= 1;
                        }
                        k[j] = (tn[i], n.child[i]);
                        len += 1;
                    }
                    for &(t, c) in &k[..len - 1] {
                        push!(t, c);
                    }
                    cur = k[len - 1].1;
                    continue;
                }
            }
            // Pop the next deferred child that can still hold a closer hit.
            loop {
                if sp == 0 {
                    return hit;
                }
                sp -= 1;
                // SAFETY: entries below `sp` were all written by `push`.
                let e = unsafe { stack[sp].assume_init() };
                if f32::from_bits((e >> 32) as u32) <= t_max {
                    cur = e as u32;
                    break;
                }
            }
        }
    }

    /// [`Bvh::any`] for a ray already prepared (see [`Traversal`]).
    #[inline(always)]
    pub(crate) fn any_prepared<L: AnyLeaf>(&self, tr: &Traversal, t_max: f32, mut leaf: L) -> bool {
        let test = tr.test();
        if let Some(hit) = self.any_head(&tr.r, &test, t_max, &mut leaf) {
            return hit;
        }
        self.any_stack(&tr.r, &test, t_max, &mut leaf)
    }

    /// [`Bvh::closest_split`] for the any-hit walk.
    #[inline(always)]
    pub(crate) fn any_split<L: AnyLeaf>(&self, tr: &Traversal, t_max: f32, leaf: &mut L) -> Option<bool> {
        self.any_head(&tr.r, &tr.test(), t_max, leaf)
    }

    /// The rest of the walk after [`Bvh::any_split`] returned `None`.
    #[inline(always)]
    pub(crate) fn any_walk<L: AnyLeaf>(&self, tr: &Traversal, t_max: f32, leaf: &mut L) -> bool {
        self.any_stack(&tr.r, &tr.test(), t_max, leaf)
    }

    /// The any-hit walk's answer when no stack walk is needed (see
    /// [`Bvh::closest_head`]).
    #[inline(always)]
    fn any_head<L: AnyLeaf>(&self, r: &RayPre, test: &NodeTest, t_max: f32, leaf: &mut L) -> Option<bool> {
        let cur = self.root;
        if cur & LEAF != 0 && (cur == EMPTY || !r.hit_box(&self.bounds, t_max)) {
            return Some(false);
        }
        let root = self.signed_root.as_deref()?;
        // One node whose children are all leaves: no stack; any order serves.
        let (_, mut mask) = test.hit_root(r, &self.nodes, root, t_max);
        while mask != 0 {
            let c = root.child[mask.trailing_zeros() as usize];
            mask &= mask - 1;
            if c != EMPTY && leaf.test(leaf_range(c), t_max) {
                return Some(true);
            }
        }
        Some(false)
    }

    /// The any-hit walk from the root with a stack of deferred children; it
    /// stops at the first leaf that blocks the ray.
    #[inline(always)]
    fn any_stack<L: AnyLeaf>(&self, r: &RayPre, test: &NodeTest, t_max: f32, leaf: &mut L) -> bool {
        let nodes = &self.nodes[..];
        let mut cur = self.root;
        // Only entries below `sp` are ever read.
        let mut stack = [MaybeUninit::<u32>::uninit(); STACK];
        let mut sp = 0;
        loop {
            if cur & LEAF != 0 {
                if cur != EMPTY && leaf.test(leaf_range(cur), t_max) {
                    return true;
                }
            } else {
                let n = &nodes[cur as usize];
                let (_, mut mask) = test.hit(r, n, t_max);
                if mask != 0 {
                    // Order does not matter for "any": take the first, defer the rest.
                    cur = n.child[mask.trailing_zeros() as usize];
                    mask &= mask - 1;
                    while mask != 0 {
                        stack[sp] = MaybeUninit::new(n.child[mask.trailing_zeros() as usize]);
                        sp += 1;
                        mask &= mask - 1;
                    }
                    continue;
                }
            }
            if sp == 0 {
                return false;
            }
            sp -= 1;
            // SAFETY: entries below `sp` were all written above.
            cur = unsafe { stack[sp].assume_init() };
        }
    }
}
