//! Single-ray traversal of the 8-wide BVH, for incoherent rays: one 8-lane pass tests all of a
//! node's children against the ray (box planes chosen by the ray's octant, so no per-axis
//! min/max), hit children are visited nearest first (closest hit) or in slot order (any hit).
//! [`Ray1x8`] prepares a packet's 8 rays for their walks at once, and also tests one child
//! against all 8 lanes by the same arithmetic, each lane in its own octant (the packet walk's
//! test for incoherent packets, `packet.rs`), or a whole node: the root, whose test is the
//! first step of every lane's walk ([`Entered`]). It also hands its lanes out as [`ListRay`]s,
//! one cache line a ray, which the breadth-first lists (`lists.rs`) test against whole nodes.

use super::stack::Stack;
use super::{
    Bvh8, HI, LO, Leaf, MAX_DEPTH, Node8, NodeRef, Plane, ROBUST, WIDTH, safe_inverse,
    safe_inverse8, slab_octant, widen,
};
use crate::math::{Ray, Vec3};
use crate::packet::RayPacket;
use crate::simd::{F32x8, Mask, bitmask, fused_mul_add, ge, lanes, lt, select, transpose8x8};
use glam::Vec3A;

/// Entries a single-ray stack may hold: each level pushes at most `WIDTH - 1` children more
/// than it pops.
const STACK: usize = (WIDTH - 1) * MAX_DEPTH + 1;

/// One ray prepared for 8-wide box tests: splatted reciprocal direction, the box planes it
/// enters (`near`) and leaves (`far`) through on each axis, and `origin * inv` on each axis
/// rounded up for the entry planes and down for the exit planes.
///
/// A plane's distance is then `plane * inv - o_inv` in one fused operation, kept as
/// `plane * inv + (-o_inv)` (the same bits: the negation is exact), so that a walk broadcasts
/// the offsets it reads without negating them first. Its product is
/// exact and the rounded-up (entry) or rounded-down (exit) `o_inv` errs only to the safe side,
/// so the one rounding left is relative to the distance itself, like that of the inverse:
/// the widening of the exit distance covers both ([`super::ROBUST`]). Embree's kernels use this
/// form without the directed offsets (and without widening).
///
/// A `FORWARD` ray (`tmin >= 0`) folds that widening into its exit planes: their reciprocal is
/// `inv * ROBUST` (one rounding more, inside the budget of [`super::ROBUST`]) and their offset
/// is that reciprocal times the origin, rounded down, so an exit distance of at least 0 comes
/// out widened, and the walk's chain of dependent operations loses the multiplication that
/// widened it after the minimum.
pub(super) struct Ray1 {
    inv: [F32x8; 3],
    inv_exit: [F32x8; 3],
    /// `-(o * inv)`, rounded up before the negation (entry planes) and down (exit planes).
    neg_oi_near: [F32x8; 3],
    neg_oi_far: [F32x8; 3],
    near: [Plane; 3],
    far: [Plane; 3],
}

impl Ray1 {
    /// The ray prepared for [`Ray1::test`] with the same `FORWARD`.
    #[inline(always)]
    pub(super) fn new<const FORWARD: bool>(ray: &Ray) -> Ray1 {
        Ray1::from_parts::<FORWARD>(ray.origin.to_array(), ray.dir.to_array().map(safe_inverse))
    }

    /// From an origin and the safe reciprocal direction ([`safe_inverse`]).
    #[inline(always)]
    pub(super) fn from_parts<const FORWARD: bool>(o: [f32; 3], inv: [f32; 3]) -> Ray1 {
        let o = Vec3A::from_array(o);
        let inv = Vec3A::from_array(inv);
        let (up, down) = directed_product(o, inv);
        let (inv_exit, down) = if FORWARD {
            let inv_exit = inv * ROBUST;
            (inv_exit, directed_product(o, inv_exit).1)
        } else {
            (inv, down)
        };
        let octant = inv.cmplt(Vec3A::ZERO).bitmask() as usize;
        let splat = |v: Vec3A| v.to_array().map(F32x8::splat);
        Ray1 {
            inv: splat(inv),
            inv_exit: splat(inv_exit),
            neg_oi_near: splat(-up),
            neg_oi_far: splat(-down),
            near: Plane::ENTRY_OF_OCTANT[octant],
            far: Plane::ENTRY_OF_OCTANT[octant ^ 7],
        }
    }

    /// The children the ray enters within `(tmin, tmax)` (bit `i` = child `i`) and their entry
    /// distances (above the exact ones by at most the relative rounding the widening covers).
    /// `FORWARD` promises `tmin >= 0` and a ray made by `new::<FORWARD>`; the entry distances
    /// are the same bits either way.
    #[inline(always)]
    pub(super) fn test<const FORWARD: bool>(
        &self,
        n: &Node8,
        tmin: F32x8,
        tmax: F32x8,
    ) -> (u32, F32x8) {
        let plane = |p: Plane, _: usize| n.bounds[p as usize];
        self.test_planes::<FORWARD>(plane, plane, tmin, tmax)
    }

    /// [`Ray1::test`] of the interior node `r`, its planes read at `r`'s byte offset from
    /// `bases` (made for this ray): the same bits.
    ///
    /// # Safety
    ///
    /// `r` is an interior reference of the tree `bases` was made from ([`Bvh8::node_at`]).
    #[inline(always)]
    unsafe fn test_at<const FORWARD: bool>(
        &self,
        bases: &PlaneBases,
        r: NodeRef,
        tmin: F32x8,
        tmax: F32x8,
    ) -> (u32, F32x8) {
        // SAFETY: the caller's promise
        let entry = |_: Plane, axis: usize| unsafe { PlaneBases::plane(bases.near[axis], r) };
        let exit = |_: Plane, axis: usize| unsafe { PlaneBases::plane(bases.far[axis], r) };
        self.test_planes::<FORWARD>(entry, exit, tmin, tmax)
    }

    /// The arithmetic of [`Ray1::test`] on planes read by `entry_plane` (the ray's entry planes,
    /// by plane and axis) and `exit_plane`.
    #[inline(always)]
    fn test_planes<const FORWARD: bool>(
        &self,
        entry_plane: impl Fn(Plane, usize) -> F32x8,
        exit_plane: impl Fn(Plane, usize) -> F32x8,
        tmin: F32x8,
        tmax: F32x8,
    ) -> (u32, F32x8) {
        let entry = |plane: Plane, axis: usize| {
            fused_mul_add(
                entry_plane(plane, axis),
                self.inv[axis],
                self.neg_oi_near[axis],
            )
        };
        let exit = |plane: Plane, axis: usize| {
            fused_mul_add(
                exit_plane(plane, axis),
                self.inv_exit[axis],
                self.neg_oi_far[axis],
            )
        };
        // a forward ray's exits come widened; its `tmax` (known before the node) is widened here
        let tmax = if FORWARD {
            tmax * F32x8::splat(ROBUST)
        } else {
            tmax
        };
        let (enter, near) =
            slab_octant::<FORWARD, FORWARD>(entry, exit, &self.near, &self.far, tmin, tmax);
        (bitmask(enter), near)
    }
}

/// One ray's entry and exit planes located in one tree's node array: the array's start moved by
/// each plane's place in a node, so that a node's plane lies at the node's byte offset from it
/// ([`NodeRef::offset`]). A walk then reads a plane in one addressing mode, where indexing the
/// array put a shift and an addition on the chain of dependent loads from one node to the next
/// (PERF.md, sitting 29).
struct PlaneBases {
    near: [*const u8; 3],
    far: [*const u8; 3],
}

// a node's planes start it, 32 bytes each, in `Plane` order: what `PlaneBases::new` counts on
const _: () = assert!(std::mem::offset_of!(Node8, bounds) == 0);

impl PlaneBases {
    /// The bases of `r`'s planes in `tree`.
    #[inline(always)]
    fn new(tree: &Bvh8, r: &Ray1) -> PlaneBases {
        let start = tree.nodes.as_ptr().cast::<u8>();
        // wrapping: an empty tree's array has no bytes to point into (and no walk reads it)
        let at = |p: Plane| start.wrapping_add(p as usize * std::mem::size_of::<F32x8>());
        PlaneBases {
            near: r.near.map(at),
            far: r.far.map(at),
        }
    }

    /// The plane of the interior node `r` read through `base`, one of these bases: the ray's
    /// entry plane on an axis (`near[axis]`) or its exit plane (`far[axis]`).
    ///
    /// # Safety
    ///
    /// `base` is one of these bases and `r` an interior reference of the tree they were made
    /// from ([`Bvh8::node_at`]).
    #[inline(always)]
    unsafe fn plane(base: *const u8, r: NodeRef) -> F32x8 {
        // SAFETY: `r`'s node lies in the array, a plane 32-byte aligned inside its 256 bytes
        unsafe { *base.add(r.offset()).cast::<F32x8>() }
    }
}

/// The 8 rays of a packet prepared for single-ray walks ([`Bvh8::closest_lane`]) as forward
/// rays (`tmin >= 0`): what a walk of [`Bvh8::closest`] computes for its one ray first
/// (reciprocal, directed offsets, octant), computed for all 8 lanes at once, so that a walk
/// only broadcasts its lane (the same bits). A ray's own preparation was about a fifth of a
/// diffuse ray's instructions on torus100k (PERF.md, sitting 20).
pub struct Ray1x8 {
    inv: [F32x8; 3],
    inv_exit: [F32x8; 3],
    neg_oi_near: [F32x8; 3],
    neg_oi_far: [F32x8; 3],
    /// Lane `l`'s direction is negative on `axis`: lane `l` of `neg[axis]`, bit `l` of
    /// `down[axis]`.
    neg: [Mask; 3],
    down: [u32; 3],
}

impl Ray1x8 {
    /// Every lane of `rays` prepared, active or not (the walks take only active ones).
    #[inline(always)]
    pub fn new(rays: &RayPacket) -> Ray1x8 {
        let inv = [rays.dir.x, rays.dir.y, rays.dir.z].map(safe_inverse8);
        Ray1x8::from_inverse([rays.origin.x, rays.origin.y, rays.origin.z], inv)
    }

    /// [`Ray1x8::new`] from the origins and the safe reciprocal directions
    /// ([`super::safe_inverse8`]) a packet walk has already computed.
    #[inline(always)]
    pub(super) fn from_inverse(o: [F32x8; 3], inv: [F32x8; 3]) -> Ray1x8 {
        let inv_exit = inv.map(|i| i * F32x8::splat(ROBUST));
        let near = std::array::from_fn(|a| directed_product8(o[a], inv[a]).0);
        let far = std::array::from_fn(|a| directed_product8(o[a], inv_exit[a]).1);
        let neg = inv.map(|i| lt(i, F32x8::splat(0.0)));
        Ray1x8 {
            inv,
            inv_exit,
            neg_oi_near: near.map(|x: F32x8| -x),
            neg_oi_far: far.map(|x: F32x8| -x),
            neg,
            down: neg.map(bitmask),
        }
    }

    /// True when every active lane of `rays` is a forward ray (`tmin >= 0`), the rays this
    /// prepares.
    #[inline(always)]
    pub fn all_forward(rays: &RayPacket) -> bool {
        let active = bitmask(rays.active);
        bitmask(ge(rays.tmin, F32x8::splat(0.0))) & active == active
    }

    /// The lanes that enter child `i` of `n` within `(tmin, tmax)` and their entry distances:
    /// [`Ray1::test`] of each lane, each in its own octant (a mask picks its planes), so the
    /// same bits as that lane's single-ray test of the child. The packet walk's test of one
    /// child for rays of mixed octants (incoherent packets, which have no frustum).
    #[inline(always)]
    pub(super) fn test_child(
        &self,
        n: &Node8,
        i: usize,
        tmin: F32x8,
        tmax: F32x8,
    ) -> (Mask, F32x8) {
        let plane = |k: usize| F32x8::splat(n.bounds[k].as_array()[i]);
        // each lane's entry plane `lo ^ ((lo ^ hi) & neg)` and exit plane `hi ^ ((lo ^ hi) &
        // neg)`: both picks from one masked difference, 4 operations an axis where two blends
        // take 6 micro-operations on Intel's cores
        let planes: [(F32x8, F32x8); 3] = std::array::from_fn(|a| {
            let (lo, hi) = (plane(LO + a), plane(HI + a));
            let flip = (lo ^ hi) & self.neg[a];
            (lo ^ flip, hi ^ flip)
        });
        let entry =
            |_: Plane, a: usize| fused_mul_add(planes[a].0, self.inv[a], self.neg_oi_near[a]);
        let exit =
            |_: Plane, a: usize| fused_mul_add(planes[a].1, self.inv_exit[a], self.neg_oi_far[a]);
        // the planes are the lanes' own (the closures ignore the octant's)
        let any_octant = Plane::ENTRY_OF_OCTANT[0];
        let tmax = tmax * F32x8::splat(ROBUST);
        slab_octant::<true, true>(entry, exit, &any_octant, &any_octant, tmin, tmax)
    }

    /// Which children of `n` each lane enters within `(tmin, tmax)`, and where: every child
    /// tested against all 8 lanes by [`Ray1x8::test_child`], so each lane's the same bits as
    /// its own single-ray test of `n` ([`Ray1::test`]). The first step of the packet's walks,
    /// taken for the 8 lanes at once ([`Bvh8::enter_root`]).
    #[inline(always)]
    fn test_node(&self, n: &Node8, tmin: F32x8, tmax: F32x8) -> Entered {
        let mut by_child = 0u64;
        let mut near = [[0.0f32; 8]; WIDTH];
        for (i, near) in near.iter_mut().enumerate() {
            let (m, d) = self.test_child(n, i, tmin, tmax);
            by_child |= (bitmask(m) as u64) << (8 * i);
            *near = d.to_array();
        }
        Entered {
            by_lane: transpose_bits8x8(by_child),
            near,
        }
    }

    /// Appends the 8 lanes of `rays`, the packet this was prepared from, to `out` as
    /// [`ListRay`]s, lane `l` at `out[len + l]` (active or not): two 8x8 transposes of the
    /// lanes' values, one record of 16 each.
    #[inline(always)]
    pub fn list_rays(&self, rays: &RayPacket, out: &mut Vec<ListRay>) {
        let [ix, iy, iz] = self.inv;
        let [nx, ny, nz] = self.neg_oi_near;
        let [fx, fy, fz] = self.neg_oi_far;
        let (o, d) = (rays.origin, rays.dir);
        let first = transpose8x8([ix, iy, iz, nx, ny, nz, fx, fy]);
        let second = transpose8x8([fz, o.x, o.y, o.z, d.x, d.y, d.z, rays.tmin]);
        out.extend(first.iter().zip(&second).map(|(a, b)| {
            let mut values = [0.0; 16];
            values[..8].copy_from_slice(&lanes(*a));
            values[8..].copy_from_slice(&lanes(*b));
            ListRay { values }
        }));
    }

    /// Lane `l` as a forward ray for [`Ray1::test`].
    #[inline(always)]
    fn lane(&self, l: usize) -> Ray1 {
        // each lane read in place (a copy of the array went through a stack slot per column)
        let splat = |v: &[F32x8; 3]| std::array::from_fn(|a| F32x8::splat(v[a].as_array()[l]));
        let octant = (0..3).fold(0, |o, a| o | (self.down[a] >> l & 1) << a) as usize;
        Ray1 {
            inv: splat(&self.inv),
            inv_exit: splat(&self.inv_exit),
            neg_oi_near: splat(&self.neg_oi_near),
            neg_oi_far: splat(&self.neg_oi_far),
            near: Plane::ENTRY_OF_OCTANT[octant],
            far: Plane::ENTRY_OF_OCTANT[octant ^ 7],
        }
    }
}

/// One forward ray of the breadth-first lists (`lists.rs`), in one cache line: what its node
/// test reads (its lane of [`Ray1x8`]: reciprocal direction and the directed offsets of the
/// entry and exit planes) and the ray itself for the leaf test. The rays of a list lie anywhere
/// in a batch of 32,768, each read again at every node it reaches: read where they lie in their
/// `Ray1x8`, one lane's values spread over seven cache lines (PERF.md, sitting 56).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub struct ListRay {
    /// Reciprocal direction (`INV`), negated rounded offsets of the entry (`NEAR`) and exit
    /// (`FAR`) planes, origin, direction and `tmin`: [`Ray1x8::list_rays`]'s two transposes.
    values: [f32; 16],
}

impl ListRay {
    const INV: usize = 0;
    const NEAR: usize = 3;
    const FAR: usize = 6;
    const ORIGIN: usize = 9;
    const DIR: usize = 12;
    const TMIN: usize = 15;

    /// The children of `n` this ray enters within `(tmin, tmax)` (as a mask, lane `i` = child
    /// `i`) and its entry distances: [`Ray1::test`] of the ray (the same bits), its planes
    /// picked by its octant at each call.
    #[inline(always)]
    pub(super) fn test(&self, n: &Node8, tmin: f32, tmax: f32) -> (Mask, F32x8) {
        let v = |k: usize| F32x8::splat(self.values[k]);
        // the entry plane of axis `a` is its upper one where the direction is negative: the
        // reciprocal's sign, as `Ray1x8::from_inverse` takes it (`lt(inv, 0)`)
        let down = |a: usize| (self.values[Self::INV + a] < 0.0) as usize;
        let entry = |_: Plane, a: usize| {
            let plane = n.bounds[LO + a + (HI - LO) * down(a)];
            fused_mul_add(plane, v(Self::INV + a), v(Self::NEAR + a))
        };
        // `inv * ROBUST` as `Ray1x8::from_inverse` computes it (the same bits)
        let exit = |_: Plane, a: usize| {
            let plane = n.bounds[HI + a - (HI - LO) * down(a)];
            fused_mul_add(
                plane,
                v(Self::INV + a) * F32x8::splat(ROBUST),
                v(Self::FAR + a),
            )
        };
        // the planes are the ray's own (the closures ignore the octant's)
        let any_octant = Plane::ENTRY_OF_OCTANT[0];
        let tmax = F32x8::splat(tmax) * F32x8::splat(ROBUST);
        slab_octant::<true, true>(
            entry,
            exit,
            &any_octant,
            &any_octant,
            F32x8::splat(tmin),
            tmax,
        )
    }

    /// The ray.
    #[inline(always)]
    pub fn ray(&self) -> Ray {
        let v = |k: usize| Vec3::new(self.values[k], self.values[k + 1], self.values[k + 2]);
        Ray::new(v(Self::ORIGIN), v(Self::DIR))
    }

    /// Where the ray starts (`tmin >= 0`).
    #[inline(always)]
    pub fn tmin(&self) -> f32 {
        self.values[Self::TMIN]
    }
}

/// The children of one node that each lane of a packet enters (`Ray1x8::test_node`, made by
/// [`Bvh8::enter_root`]): byte `l` of `by_lane` holds lane `l`'s mask (bit `i` = child `i`),
/// `near[i][l]` its entry distance into child `i`.
pub struct Entered {
    by_lane: u64,
    near: [[f32; 8]; WIDTH],
}

impl Entered {
    /// Lane `l`'s children (bit `i` = child `i`).
    #[inline(always)]
    fn mask(&self, l: usize) -> u32 {
        (self.by_lane >> (8 * l)) as u32 & 0xff
    }

    /// The lanes that enter a child at all (bit `l` = lane `l`): the others hit nothing in the
    /// tree.
    #[inline(always)]
    pub fn lanes(&self) -> u32 {
        (0..8).fold(0, |m, l| m | u32::from(self.mask(l) != 0) << l)
    }
}

/// The transpose of an 8x8 bit matrix held row by row in the bytes of a `u64` (bit `c` of
/// byte `r` goes to bit `r` of byte `c`): three exchanges of blocks across the diagonal (Hacker's
/// Delight, 7-3).
#[inline(always)]
fn transpose_bits8x8(mut x: u64) -> u64 {
    let mut t = (x ^ (x >> 7)) & 0x00AA_00AA_00AA_00AA;
    x ^= t ^ (t << 7);
    t = (x ^ (x >> 14)) & 0x0000_CCCC_0000_CCCC;
    x ^= t ^ (t << 14);
    t = (x ^ (x >> 28)) & 0x0000_0000_F0F0_F0F0;
    x ^ t ^ (t << 28)
}

/// [`directed_product`] of one axis for 8 lanes (the same operations, so the same bits).
#[inline(always)]
fn directed_product8(o: F32x8, inv: F32x8) -> (F32x8, F32x8) {
    let p = o * inv;
    let slack = p.abs() * F32x8::splat(2.0 * f32::EPSILON) + F32x8::splat(f32::MIN_POSITIVE);
    let finite = lt(p.abs(), F32x8::splat(f32::INFINITY));
    (
        select(finite, p + slack, F32x8::splat(f32::INFINITY)),
        select(finite, p - slack, F32x8::splat(f32::NEG_INFINITY)),
    )
}

/// `o * inv` on each axis rounded up and rounded down: the rounded product moved away by two
/// of its units in the last place, more than its rounding error (half a unit) plus that of the
/// move; the absolute term covers products that round to a subnormal or zero. An infinite
/// product gives `(+inf, -inf)`, so that axis culls nothing: its entry distances are `-inf`,
/// its exit ones `+inf`.
#[inline(always)]
fn directed_product(o: Vec3A, inv: Vec3A) -> (Vec3A, Vec3A) {
    let p = o * inv;
    let slack = p.abs() * (2.0 * f32::EPSILON) + Vec3A::splat(f32::MIN_POSITIVE);
    let finite = p.is_finite_mask();
    (
        Vec3A::select(finite, p + slack, Vec3A::INFINITY),
        Vec3A::select(finite, p - slack, Vec3A::NEG_INFINITY),
    )
}

impl Bvh8 {
    /// The closest hit of one ray: visits every leaf the ray may hit nearer than `tmax`,
    /// nearest child first; `leaf(leaf, tmax)` tests the leaf's primitives and lowers `tmax`
    /// where it finds a nearer hit; `touch(leaf)` starts fetching a leaf the walk pushes for
    /// later (a leaf is fetched while the walk tests the nearer children).
    #[inline(always)]
    pub fn closest(
        &self,
        ray: &Ray,
        tmin: f32,
        tmax: &mut f32,
        leaf: impl FnMut(Leaf, &mut f32),
        touch: impl Fn(Leaf),
    ) {
        if tmin >= 0.0 {
            self.closest_walk::<true>(ray, tmin, tmax, leaf, &touch);
        } else {
            self.closest_walk::<false>(ray, tmin, tmax, leaf, &touch);
        }
    }

    /// The root's children each lane of `rays` enters within `(tmin, tmax)` (the lanes' own
    /// limits, `tmin >= 0`), tested for the 8 lanes at once; `None` when the root is a leaf or
    /// the tree is empty. [`Bvh8::closest_lane`] starts a lane's walk from it.
    #[inline(always)]
    pub fn enter_root(&self, rays: &Ray1x8, tmin: F32x8, tmax: F32x8) -> Option<Entered> {
        (!self.root.is_leaf()).then(|| rays.test_node(&self.nodes[self.root.index()], tmin, tmax))
    }

    /// [`Bvh8::closest`] for lane `l` of a packet prepared by [`Ray1x8::new`], whose `tmin`
    /// must be at least 0 (a forward ray): the same walk, without preparing the ray again. With
    /// `root`, the packet's test of the root ([`Bvh8::enter_root`], made with this lane's
    /// `tmin` and `tmax`), the walk starts at its second step.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub fn closest_lane(
        &self,
        rays: &Ray1x8,
        root: Option<&Entered>,
        l: usize,
        tmin: f32,
        tmax: &mut f32,
        leaf: impl FnMut(Leaf, &mut f32),
        touch: impl Fn(Leaf),
    ) {
        debug_assert!(tmin >= 0.0);
        let start = |stack: &mut Stack<(NodeRef, f32), STACK>| match root {
            Some(e) => {
                let n = &self.nodes[self.root.index()];
                self.enter(n, e.mask(l), |c| e.near[c][l], stack, &touch)
            }
            None => Some(self.root),
        };
        self.closest_from::<true>(&rays.lane(l), tmin, tmax, leaf, &touch, start);
    }

    /// [`Bvh8::closest`], `FORWARD` when `tmin >= 0` ([`super::widen_exit`]).
    #[inline(always)]
    fn closest_walk<const FORWARD: bool>(
        &self,
        ray: &Ray,
        tmin: f32,
        tmax: &mut f32,
        leaf: impl FnMut(Leaf, &mut f32),
        touch: &impl Fn(Leaf),
    ) {
        let r = Ray1::new::<FORWARD>(ray);
        self.closest_from::<FORWARD>(&r, tmin, tmax, leaf, touch, |_| Some(self.root));
    }

    /// The walk of [`Bvh8::closest`] for a prepared ray, from where `start` puts it (the root,
    /// or the nearest child of a root already tested, the others pushed; `None`: nowhere).
    #[inline(always)]
    fn closest_from<const FORWARD: bool>(
        &self,
        r: &Ray1,
        tmin: f32,
        tmax: &mut f32,
        mut leaf: impl FnMut(Leaf, &mut f32),
        touch: &impl Fn(Leaf),
        start: impl FnOnce(&mut Stack<(NodeRef, f32), STACK>) -> Option<NodeRef>,
    ) {
        if self.root.is_empty() {
            return;
        }
        let tmin8 = F32x8::splat(tmin);
        let bases = PlaneBases::new(self, r);
        let mut stack: Stack<(NodeRef, f32), STACK> = Stack::new();
        let Some(mut cur) = start(&mut stack) else {
            return;
        };
        loop {
            let next = if cur.is_leaf() {
                leaf(cur.as_leaf(), tmax);
                None
            } else {
                // SAFETY: `cur` is the root or a child reference read from this tree's nodes
                // (by `start`, `descend` or through the stack they fill)
                unsafe { self.descend::<FORWARD>(r, &bases, cur, tmin8, *tmax, &mut stack, touch) }
            };
            cur = match next {
                Some(c) => c,
                None => match pop_nearer(&mut stack, *tmax) {
                    Some(c) => c,
                    None => return,
                },
            };
        }
    }

    /// One step down from interior node `cur` for a closest-hit walk: the nearest child the
    /// ray enters before `tmax`, the other entered children pushed farthest first; `None` when
    /// it enters none. Pushed interior nodes are prefetched here, pushed leaves by `touch`.
    ///
    /// # Safety
    ///
    /// `cur` is an interior reference of this tree ([`Bvh8::node_at`]), `bases` made from it
    /// for `r`.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    unsafe fn descend<const FORWARD: bool>(
        &self,
        r: &Ray1,
        bases: &PlaneBases,
        cur: NodeRef,
        tmin8: F32x8,
        tmax: f32,
        stack: &mut Stack<(NodeRef, f32), STACK>,
        touch: &impl Fn(Leaf),
    ) -> Option<NodeRef> {
        // SAFETY: the caller's promise
        let (mask, near) = unsafe { r.test_at::<FORWARD>(bases, cur, tmin8, F32x8::splat(tmax)) };
        let near = near.to_array();
        // SAFETY: the caller's promise
        let n = unsafe { self.node_at(cur) };
        self.enter(n, mask, |c| near[c], stack, touch)
    }

    /// The step of [`Bvh8::descend`] after the test: of the children in `mask` (entry
    /// distances `near(child)`), the nearest, the others pushed farthest first.
    #[inline(always)]
    fn enter(
        &self,
        n: &Node8,
        mask: u32,
        near: impl Fn(usize) -> f32,
        stack: &mut Stack<(NodeRef, f32), STACK>,
        touch: &impl Fn(Leaf),
    ) -> Option<NodeRef> {
        if mask == 0 {
            return None;
        }
        let c0 = mask.trailing_zeros() as usize;
        let rest = mask & (mask - 1);
        if rest == 0 {
            return Some(n.child[c0]);
        }
        let c1 = rest.trailing_zeros() as usize;
        let rest = rest & (rest - 1);
        if rest == 0 {
            // two: the farther waits on the stack
            let (a, b) = ((n.child[c0], near(c0)), (n.child[c1], near(c1)));
            let (first, second) = if a.1 <= b.1 { (a, b) } else { (b, a) };
            self.prefetch(second.0, touch);
            stack.push(second);
            return Some(first.0);
        }
        // three or more: sort them farthest first, push all but the nearest
        let mut keys = [0u64; WIDTH];
        keys[0] = sort_key(near(c0), c0);
        keys[1] = sort_key(near(c1), c1);
        let mut count = 2;
        let mut m = rest;
        while m != 0 {
            let j = m.trailing_zeros() as usize;
            m &= m - 1;
            keys[count] = sort_key(near(j), j);
            count += 1;
        }
        sort_keys_descending(&mut keys[..count]);
        for &k in &keys[..count - 1] {
            let c = (k & 7) as usize;
            let h = (n.child[c], near(c));
            self.prefetch(h.0, touch);
            stack.push(h);
        }
        Some(n.child[(keys[count - 1] & 7) as usize])
    }

    /// Single-ray any hit: true as soon as `leaf(leaf)` reports a blocker before `tmax`.
    #[inline(always)]
    pub fn occluded(
        &self,
        ray: &Ray,
        tmin: f32,
        tmax: f32,
        leaf: impl FnMut(Leaf) -> bool,
    ) -> bool {
        if tmin >= 0.0 {
            self.occluded_walk::<true>(ray, tmin, tmax, leaf)
        } else {
            self.occluded_walk::<false>(ray, tmin, tmax, leaf)
        }
    }

    /// [`Bvh8::occluded`], `FORWARD` when `tmin >= 0` ([`super::widen_exit`]).
    #[inline(always)]
    fn occluded_walk<const FORWARD: bool>(
        &self,
        ray: &Ray,
        tmin: f32,
        tmax: f32,
        mut leaf: impl FnMut(Leaf) -> bool,
    ) -> bool {
        if self.root.is_empty() {
            return false;
        }
        let r = Ray1::new::<FORWARD>(ray);
        let bases = PlaneBases::new(self, &r);
        let (tmin8, tmax8) = (F32x8::splat(tmin), F32x8::splat(tmax));
        let mut stack: Stack<NodeRef, STACK> = Stack::new();
        let mut cur = self.root;
        loop {
            if cur.is_leaf() {
                if leaf(cur.as_leaf()) {
                    return true;
                }
            } else {
                // SAFETY: `cur` is the root or a child reference read from this tree's nodes
                // (here or through the stack)
                let (mut mask, _) = unsafe { r.test_at::<FORWARD>(&bases, cur, tmin8, tmax8) };
                // SAFETY: as above
                let n = unsafe { self.node_at(cur) };
                if mask != 0 {
                    let i = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    while mask != 0 {
                        let j = mask.trailing_zeros() as usize;
                        mask &= mask - 1;
                        stack.push(n.child[j]);
                    }
                    cur = n.child[i];
                    continue;
                }
            }
            match stack.pop() {
                Some(c) => cur = c,
                None => return false,
            }
        }
    }
}

/// Pops entries until one the ray may still enter before `tmax`.
#[inline(always)]
fn pop_nearer(stack: &mut Stack<(NodeRef, f32), STACK>, tmax: f32) -> Option<NodeRef> {
    loop {
        match stack.pop() {
            None => return None,
            Some((c, near)) if near <= widen(tmax) => return Some(c),
            Some(_) => {}
        }
    }
}

/// A child's place in its walk's order: its entry distance's bits mapped to integers of the
/// same order (negative distances too), then its slot, so that of equal distances the lower
/// slot counts as nearer.
#[inline(always)]
fn sort_key(near: f32, slot: usize) -> u64 {
    let b = near.to_bits();
    let ordered = b ^ ((b as i32 >> 31) as u32 | 0x8000_0000);
    u64::from(ordered) << 32 | slot as u64
}

/// Sorts a few keys largest first: three or four by a network of compare-exchanges (no
/// branch on the data), more by insertion.
#[inline(always)]
fn sort_keys_descending(k: &mut [u64]) {
    #[inline(always)]
    fn exchange(k: &mut [u64], i: usize, j: usize) {
        let (a, b) = (k[i], k[j]);
        (k[i], k[j]) = (a.max(b), a.min(b));
    }
    match k.len() {
        3 => {
            exchange(k, 0, 1);
            exchange(k, 1, 2);
            exchange(k, 0, 1);
        }
        4 => {
            exchange(k, 0, 1);
            exchange(k, 2, 3);
            exchange(k, 0, 2);
            exchange(k, 1, 3);
            exchange(k, 1, 2);
        }
        _ => {
            for i in 1..k.len() {
                let x = k[i];
                let mut j = i;
                while j > 0 && k[j - 1] < x {
                    k[j] = k[j - 1];
                    j -= 1;
                }
                k[j] = x;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{PlaneBases, Ray1, Ray1x8};
    use crate::bvh::build::{BuildSettings, LeafSink, build};
    use crate::bvh::{Aabb, HI, LO, Node8, NodeRef, WIDTH};
    use crate::math::{Ray, Vec3};
    use crate::packet::RayPacket;
    use crate::simd::F32x8;
    use crate::test_rng::Rng;

    /// Every field of a prepared ray as bits (planes as their indices).
    fn bits(r: &Ray1) -> Vec<u32> {
        let mut v = Vec::new();
        for c in [&r.inv, &r.inv_exit, &r.neg_oi_near, &r.neg_oi_far] {
            for x in c {
                v.extend(x.to_array().map(f32::to_bits));
            }
        }
        v.extend(r.near.iter().chain(&r.far).map(|&p| p as u32));
        v
    }

    /// A packet's lanes prepared all 8 at once are the rays prepared one by one, bit for bit:
    /// origins near and far (up to 1e6), direction components of every sign, zero (both
    /// signs), tiny (below the 1e-30 that `safe_inverse` replaces) and infinite.
    #[test]
    fn a_packet_prepared_at_once_is_its_rays_prepared_one_by_one() {
        let mut rng = Rng(0x9e37_79b9);
        let specials = [
            0.0,
            -0.0,
            1e-31,
            -1e-31,
            1e-30,
            f32::INFINITY,
            f32::NEG_INFINITY,
        ];
        for case in 0..2000 {
            let scale = [1.0, 1e3, 1e6][case % 3];
            let rays: [Ray; 8] = std::array::from_fn(|l| {
                let o =
                    Vec3::from_array(std::array::from_fn(|_| rng.range64(-scale, scale) as f32));
                let d: [f32; 3] = std::array::from_fn(|a| {
                    if (case + l + a) % 5 == 0 {
                        specials[(case * 7 + l * 3 + a) % specials.len()]
                    } else {
                        rng.range64(-1.0, 1.0) as f32
                    }
                });
                Ray::new(o, Vec3::from_array(d))
            });
            let packet = RayPacket::from_rays(&rays, 0.0);
            let prepared = Ray1x8::new(&packet);
            for (l, ray) in rays.iter().enumerate() {
                assert_eq!(
                    bits(&prepared.lane(l)),
                    bits(&Ray1::new::<true>(ray)),
                    "case {case}, lane {l}: {ray:?}"
                );
            }
        }
    }

    /// A packet's test of one child, each lane in its own octant, gives each lane's own
    /// single-ray test of that child bit for bit (mask and entry distance), for rays of every
    /// octant mixed in one packet, boxes they start inside, rays through a box's corner, and
    /// per-lane `tmin` and `tmax`; so does its test of a whole node (the first step of the
    /// lanes' walks).
    #[test]
    fn a_packet_child_test_is_each_lanes_single_ray_test() {
        let mut rng = Rng(0x51ed_2701);
        for case in 0..500 {
            // In every fourth case, half the lanes aim at a corner of a box as the node
            // stores it: where such a ray touches the box at the corner alone, it enters and
            // leaves at one distance, and the exit's widening is what keeps the box entered.
            let corners = case % 4 == 2;
            let boxes: [Aabb; WIDTH] = std::array::from_fn(|k| {
                let a: [f32; 3] = std::array::from_fn(|_| rng.range64(-4.0, 4.0) as f32);
                let mut b: [f32; 3] = std::array::from_fn(|_| rng.range64(-4.0, 4.0) as f32);
                // in every other case, boxes of no thickness on one axis (an axis-aligned
                // triangle's): a ray crossing one enters and leaves it there at one distance
                if case % 2 == 1 {
                    b[k % 3] = a[k % 3];
                }
                let (a, b) = (Vec3::from_array(a), Vec3::from_array(b));
                Aabb {
                    min: a.min(b),
                    max: a.max(b),
                }
            });
            let n = Node8::new(&boxes.map(|b| (NodeRef::EMPTY, b)));
            let rays: [Ray; 8] = std::array::from_fn(|l| {
                let o = Vec3::from_array(std::array::from_fn(|_| rng.range64(-6.0, 6.0) as f32));
                if corners && l % 2 == 0 {
                    // the node's planes (its boxes padded outward), one of each axis's two
                    let pick = (case / 4 + l) % 8;
                    let corner = Vec3::from_array(std::array::from_fn(|a| {
                        let plane = if pick >> a & 1 == 1 { HI + a } else { LO + a };
                        n.bounds[plane].to_array()[l]
                    }));
                    let o = if l % 4 == 0 { Vec3::ZERO } else { o };
                    let d = corner - o;
                    return Ray::new(o, if d == Vec3::ZERO { Vec3::X } else { d });
                }
                let mut d: [f32; 3] = std::array::from_fn(|_| rng.range64(-1.0, 1.0) as f32);
                if (case + l) % 6 == 0 {
                    d[l % 3] = 0.0;
                }
                Ray::new(o, Vec3::from_array(d).normalize_or(Vec3::X))
            });
            let mut packet = RayPacket::from_rays(&rays, 0.0);
            let tmin: [f32; 8] =
                std::array::from_fn(|_| [0.0, 1e-3, 0.5][rng.range64(0.0, 2.99) as usize]);
            packet.tmin = F32x8::new(tmin);
            let tmax: [f32; 8] = std::array::from_fn(|_| rng.range64(0.5, 20.0) as f32);
            let prepared = Ray1x8::new(&packet);
            let mut list = Vec::new();
            prepared.list_rays(&packet, &mut list);
            assert_eq!(list.len(), 8);
            for (l, ray) in rays.iter().enumerate() {
                let r = list[l].ray();
                assert_eq!((r.origin, r.dir), (ray.origin, ray.dir), "case {case}");
                assert_eq!(list[l].tmin().to_bits(), tmin[l].to_bits());
            }
            let (t0, t1) = (F32x8::new(tmin), F32x8::new(tmax));
            let node = prepared.test_node(&n, t0, t1);
            for i in 0..WIDTH {
                let (mask, near) = prepared.test_child(&n, i, t0, t1);
                for (l, ray) in rays.iter().enumerate() {
                    let (t0, t1) = (F32x8::splat(tmin[l]), F32x8::splat(tmax[l]));
                    let (m1, n1) = Ray1::new::<true>(ray).test::<true>(&n, t0, t1);
                    // a ray from the origin through a stored corner meets that box at t = 1
                    if corners && l % 4 == 0 && i == l && tmin[l] <= 1.0 && tmax[l] >= 1.0 {
                        assert_eq!(m1 >> i & 1, 1, "case {case}, lane {l}: its corner's box");
                    }
                    assert_eq!(
                        crate::simd::bitmask(mask) >> l & 1,
                        m1 >> i & 1,
                        "case {case}, child {i}, lane {l}"
                    );
                    assert_eq!(near.to_array()[l].to_bits(), n1.to_array()[i].to_bits());
                    // the lane as a record (the breadth-first lists' test)
                    let (m2, n2) = list[l].test(&n, tmin[l], tmax[l]);
                    assert_eq!(crate::simd::bitmask(m2), m1, "case {case}");
                    assert_eq!(n2.to_array()[i].to_bits(), n1.to_array()[i].to_bits());
                    // the whole node at once: lane l's byte and its row of distances
                    assert_eq!(node.mask(l), m1, "case {case}");
                    assert_eq!(node.near[i][l].to_bits(), n1.to_array()[i].to_bits());
                }
            }
        }
    }

    /// The empty slots of a node (inverted boxes) are entered by no lane, whatever the ray:
    /// every octant, direction components of either zero, origins inside the children, `tmax`
    /// infinite. The packet walk tests all 8 slots of a node on this ground
    /// (`packet::hit_children_all`), as the whole-node tests do.
    #[test]
    fn empty_slots_are_entered_by_no_ray() {
        let mut rng = Rng(0x0e47_5107);
        for case in 0..300 {
            let children = 1 + case % (WIDTH - 1);
            let boxes: Vec<(NodeRef, Aabb)> = (0..children)
                .map(|_| {
                    let a =
                        Vec3::from_array(std::array::from_fn(|_| rng.range64(-4.0, 4.0) as f32));
                    let b =
                        Vec3::from_array(std::array::from_fn(|_| rng.range64(-4.0, 4.0) as f32));
                    (
                        NodeRef::EMPTY,
                        Aabb {
                            min: a.min(b),
                            max: a.max(b),
                        },
                    )
                })
                .collect();
            let n = Node8::new(&boxes);
            let rays: [Ray; 8] = std::array::from_fn(|l| {
                let o = Vec3::from_array(std::array::from_fn(|_| rng.range64(-6.0, 6.0) as f32));
                let mut d: [f32; 3] = std::array::from_fn(|_| rng.range64(-1.0, 1.0) as f32);
                // zeros of both signs on one or two axes
                match (case + l) % 4 {
                    0 => d[l % 3] = 0.0,
                    1 => d[l % 3] = -0.0,
                    2 => (d[l % 3], d[(l + 1) % 3]) = (0.0, -0.0),
                    _ => {}
                }
                Ray {
                    origin: o,
                    dir: Vec3::from_array(d),
                }
            });
            let packet = RayPacket::from_rays(&rays, 0.0);
            let prepared = Ray1x8::new(&packet);
            let mut list = Vec::new();
            prepared.list_rays(&packet, &mut list);
            let (t0, t1) = (F32x8::splat(0.0), F32x8::splat(f32::INFINITY));
            for i in children..WIDTH {
                let (mask, _) = prepared.test_child(&n, i, t0, t1);
                assert_eq!(crate::simd::bitmask(mask), 0, "case {case}, slot {i}");
            }
            for (l, ray) in list.iter().enumerate() {
                let (mask, _) = ray.test(&n, 0.0, f32::INFINITY);
                assert_eq!(
                    crate::simd::bitmask(mask) >> children,
                    0,
                    "case {case}, lane {l}"
                );
            }
        }
    }

    /// Children come out of the walk's sort farthest first, of equal distances the higher slot
    /// first (the lower is visited first): distances of both signs, zeros, infinities and
    /// ties, every count of entered children.
    #[test]
    fn entered_children_sort_farthest_first_ties_by_slot() {
        let mut rng = Rng(0x3c6e_f372);
        let values = [
            -1e30,
            -2.5,
            -1.0,
            -0.0,
            0.0,
            1e-40,
            0.5,
            1.0,
            7.0,
            1e30,
            f32::INFINITY,
        ];
        for case in 0..5000 {
            let count = 1 + case % 8;
            let mut slots: Vec<usize> = (0..8).collect();
            // a random subset of the slots, in slot order (as the walk gathers them)
            for i in (1..8).rev() {
                slots.swap(i, rng.next() as usize % (i + 1));
            }
            let mut slots = slots[..count].to_vec();
            slots.sort();
            let near: Vec<f32> = slots
                .iter()
                .map(|_| values[rng.next() as usize % values.len()])
                .collect();
            let mut keys: Vec<u64> = slots
                .iter()
                .zip(&near)
                .map(|(&c, &d)| super::sort_key(d, c))
                .collect();
            super::sort_keys_descending(&mut keys);
            let got: Vec<usize> = keys.iter().map(|k| (k & 7) as usize).collect();
            let mut want: Vec<(f32, usize)> = near.iter().copied().zip(slots.clone()).collect();
            // farthest first; ties (-0 and 0 apart) by slot, the higher first
            want.sort_by(|a, b| b.0.total_cmp(&a.0).then(b.1.cmp(&a.1)));
            let want: Vec<usize> = want.iter().map(|w| w.1).collect();
            assert_eq!(got, want, "case {case}: {near:?} at {slots:?}");
        }
    }

    /// The 8x8 bit transpose moves bit `c` of byte `r` to bit `r` of byte `c`, for single bits
    /// and for random matrices.
    #[test]
    fn the_bit_transpose_moves_each_bit_across_the_diagonal() {
        let naive = |x: u64| {
            let mut y = 0u64;
            for r in 0..8 {
                for c in 0..8 {
                    y |= (x >> (8 * r + c) & 1) << (8 * c + r);
                }
            }
            y
        };
        for b in 0..64 {
            assert_eq!(super::transpose_bits8x8(1 << b), naive(1 << b), "bit {b}");
        }
        let mut rng = Rng(0x7f4a_7c15);
        for _ in 0..1000 {
            let x = u64::from(rng.next()) << 32 | u64::from(rng.next());
            assert_eq!(super::transpose_bits8x8(x), naive(x));
        }
    }

    /// Whether the ray `o + t d`, `t` in `[tmin, tmax]`, meets the closed box, in `f64` (exact
    /// reciprocals, no widening), and by how much: the length of the overlap of its slabs
    /// relative to the distances involved (negative for a miss).
    fn enters(o: Vec3, d: Vec3, b: &Aabb, tmin: f64, tmax: f64) -> f64 {
        let (mut t0, mut t1) = (tmin, tmax);
        for a in 0..3 {
            let (o, d) = (f64::from(o[a]), f64::from(d[a]));
            let (lo, hi) = (f64::from(b.min[a]), f64::from(b.max[a]));
            if d == 0.0 {
                if o < lo || o > hi {
                    return -1.0;
                }
                continue;
            }
            let (x, y) = ((lo - o) / d, (hi - o) / d);
            (t0, t1) = (t0.max(x.min(y)), t1.min(x.max(y)));
        }
        (t1 - t0) / t0.abs().max(t1.abs()).max(1e-30)
    }

    /// The 8-wide node test never culls a child box the ray meets, by however little: origins
    /// far from the boxes (up to 1e6, where `origin * inv` carries a large absolute error),
    /// direction components of zero, boxes only grazed, negative `tmin` (orthographic rays).
    /// Boxes are stored unpadded, so only the test's own error bound is exercised. For
    /// `tmin >= 0` the forward test (widening folded into the exit planes) gives the same
    /// entry distances and must keep every met box too.
    #[test]
    fn the_node_test_never_culls_a_box_the_ray_meets() {
        let mut rng = Rng(0x2545_f491);
        let (mut met, mut grazed, mut forward) = (0, 0, 0);
        for case in 0..20_000 {
            let scale = [1.0, 1e2, 1e4, 1e6][case % 4];
            let o = Vec3::from_array(std::array::from_fn(|_| rng.range64(-scale, scale) as f32));
            let mut d: [f32; 3] = std::array::from_fn(|_| rng.range64(-1.0, 1.0) as f32);
            if case % 5 == 0 {
                d[case / 5 % 3] = 0.0;
            }
            let d = Vec3::from_array(d).normalize_or(Vec3::X);
            let tmin = [1e-4, 0.0, -1e3][case % 3];
            let tmax = if case % 7 == 0 { 1e3 } else { f64::INFINITY };
            // boxes around points of the ray, of every size relative to the distance, nudged
            // sideways so that many are only grazed
            let boxes: [Aabb; WIDTH] = std::array::from_fn(|_| {
                let t = rng.range64(-0.5, 2.0) * 2.0 * scale;
                let size = scale * 10f64.powf(rng.range64(-7.0, 0.0));
                let p: [f64; 3] = std::array::from_fn(|a| {
                    f64::from(o[a]) + t * f64::from(d[a]) + size * rng.range64(-1.0, 1.0)
                });
                let lo = p.map(|x| (x - size * rng.range64(0.0, 1.0)) as f32);
                let hi = p.map(|x| (x + size * rng.range64(0.0, 1.0)) as f32);
                Aabb {
                    min: Vec3::from_array(lo),
                    max: Vec3::from_array(hi),
                }
            });
            let mut n = Node8::new(&[(NodeRef::EMPTY, boxes[0]); WIDTH]);
            for a in 0..3 {
                n.bounds[a] = F32x8::new(boxes.map(|b| b.min[a]));
                n.bounds[3 + a] = F32x8::new(boxes.map(|b| b.max[a]));
            }
            let ray = Ray::new(o, d);
            let (t0, t1) = (F32x8::splat(tmin as f32), F32x8::splat(tmax as f32));
            let (mask, near) = Ray1::new::<false>(&ray).test::<false>(&n, t0, t1);
            // forward rays (the widening folded into the exit planes): the same entry
            // distances, and they too must keep every box they meet
            let fmask = if tmin >= 0.0 {
                let (fmask, fnear) = Ray1::new::<true>(&ray).test::<true>(&n, t0, t1);
                assert_eq!(
                    fnear.to_array().map(f32::to_bits),
                    near.to_array().map(f32::to_bits)
                );
                forward += 1;
                fmask
            } else {
                mask
            };
            for (i, b) in boxes.iter().enumerate() {
                let overlap = enters(o, d, b, tmin, tmax);
                if overlap >= 1e-12 {
                    met += 1;
                    grazed += usize::from(overlap < 1e-4);
                    for (m, kind) in [(mask, "general"), (fmask, "forward")] {
                        assert!(
                            m >> i & 1 == 1,
                            "case {case}: box {b:?} culled ({kind}), ray {o} + t {d}, \
                             overlap {overlap:e}"
                        );
                    }
                }
            }
        }
        assert!(
            met > 40_000 && grazed > 10_000 && forward > 10_000,
            "{met} boxes met, {grazed} grazed, {forward} forward rays"
        );
    }

    /// A sink that stores nothing (the walks below never reach a leaf's contents).
    struct NoSink;

    impl LeafSink for NoSink {
        fn leaf(&self, _tag: u8, _prims: &[u32]) -> u32 {
            0
        }
    }

    /// The walks' unchecked reads find what indexing finds: every node of a built tree, read at
    /// its reference's byte offset, is the node at its index, and the test of its planes through
    /// a ray's plane bases gives the bits of the test of the indexed node, for rays of every
    /// octant, forward or not.
    #[test]
    fn a_node_read_at_its_offset_is_the_node_at_its_index() {
        let mut rng = Rng(0x5851_f42d);
        let boxes: Vec<Aabb> = (0..3000)
            .map(|_| {
                let c: [f32; 3] = std::array::from_fn(|_| rng.range64(-10.0, 10.0) as f32);
                let h = rng.range64(0.01, 0.5) as f32;
                Aabb {
                    min: Vec3::from_array(c) - Vec3::splat(h),
                    max: Vec3::from_array(c) + Vec3::splat(h),
                }
            })
            .collect();
        let tree = build(
            boxes.len(),
            |i| (boxes[i], 0),
            &BuildSettings::default(),
            &NoSink,
        );
        assert!(tree.nodes.len() > 50, "{} nodes", tree.nodes.len());
        for case in 0..64 {
            let o = Vec3::from_array(std::array::from_fn(|_| rng.range64(-12.0, 12.0) as f32));
            let d = Vec3::from_array(std::array::from_fn(|_| rng.range64(-1.0, 1.0) as f32));
            let ray = Ray::new(o, d.normalize_or(Vec3::Y));
            let (t0, t1) = (
                F32x8::splat([0.0, 1e-4, -1.0][case % 3]),
                F32x8::splat(30.0),
            );
            let (general, forward) = (Ray1::new::<false>(&ray), Ray1::new::<true>(&ray));
            let (gb, fb) = (
                PlaneBases::new(&tree, &general),
                PlaneBases::new(&tree, &forward),
            );
            let bits = |(mask, near): (u32, F32x8)| (mask, near.to_array().map(f32::to_bits));
            for (i, n) in tree.nodes.iter().enumerate() {
                let r = NodeRef::node(i as u32);
                assert_eq!(r.index(), i);
                assert_eq!(r.offset(), i * size_of::<Node8>());
                // SAFETY: `r` names node `i` of `tree`, the tree the bases were made from
                let (at, read) =
                    unsafe { (general.test_at::<false>(&gb, r, t0, t1), tree.node_at(r)) };
                assert!(std::ptr::eq(read, n));
                assert_eq!(bits(at), bits(general.test::<false>(n, t0, t1)));
                if case % 3 != 2 {
                    // SAFETY: as above
                    let at = unsafe { forward.test_at::<true>(&fb, r, t0, t1) };
                    assert_eq!(bits(at), bits(forward.test::<true>(n, t0, t1)));
                }
            }
        }
    }
}
