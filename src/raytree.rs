//! The ray tree of one pixel, the lecture's debugging tool: every ray spawned for the pixel, by
//! kind (eye, shadow, reflected, transmitted), with where it starts and ends and what it hit.
//! A tracer asked for a tree records into a [`RayTree`] while it traces that one pixel; the CLI
//! writes the tree as JSON ([`RayTree::to_json`]) and draws it over a witness view
//! (`witness/`).
//!
//! ```text
//! tracer --add_ray / add_shadow--> RayTree { segments, parent links } --to_json--> FILE.json
//!                                     |--canonical / approx_eq--> tracer equivalence tests
//!                                     '--witness/--> FILE.png
//! ```
//!
//! The tree is a flat list of segments with explicit parent links, and nothing here assumes the
//! order in which a tracer records them: the recursive reference tracer records depth first, a
//! wavefront tracer bounce by bounce. The only ordering a recording must respect is that a parent
//! is added before its children (which any tracer does, since a child is spawned from its
//! parent's hit). [`RayTree::canonical`] puts any valid recording in one order, so trees from
//! different tracers compare with [`RayTree::approx_eq`].
//!
//! End points are decided here and nowhere else ([`ray_end`], [`shadow_end`]):
//! - a ray that hits a surface ends at the hit point;
//! - a ray that escapes ends [`ESCAPE_LENGTH`] along its unit direction;
//! - an unblocked shadow ray ends at the point light, or [`ESCAPE_LENGTH`] towards a directional
//!   light;
//! - a blocked shadow ray ends at its first (nearest) occluder, whose primitive and material it
//!   names. "Blocked" means some surface lies between the point and the light; with transparent
//!   shadows the light may still pass, tinted.

use std::fmt::Write as _;

use crate::error::{Error, Result};
use crate::intersect::Hit;
use crate::math::{Ray, Vec3};

/// Where a segment ends when its ray escapes the scene, or when it is a shadow ray towards a
/// directional light (distance along the unit direction, in scene units).
pub const ESCAPE_LENGTH: f32 = 100.0;

/// Index of a segment in [`RayTree::segments`], as returned by the `add_*` methods.
pub type SegmentId = usize;

/// The kind of a ray; the course draws eye rays gray, shadow rays green, reflected red,
/// transmitted blue.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum SegmentKind {
    /// The primary ray from the camera through the pixel.
    Eye,
    /// A ray from a surface point towards a light.
    Shadow,
    /// A mirror ray.
    Reflected,
    /// A refracted ray.
    Transmitted,
}

impl SegmentKind {
    /// Every kind, in the canonical order.
    pub const ALL: [SegmentKind; 4] = [
        SegmentKind::Eye,
        SegmentKind::Shadow,
        SegmentKind::Reflected,
        SegmentKind::Transmitted,
    ];

    /// The name used in JSON and statistics.
    pub fn name(self) -> &'static str {
        match self {
            SegmentKind::Eye => "eye",
            SegmentKind::Shadow => "shadow",
            SegmentKind::Reflected => "reflected",
            SegmentKind::Transmitted => "transmitted",
        }
    }

    /// Position in [`SegmentKind::ALL`] (for per-kind counters).
    pub fn index(self) -> usize {
        self as usize
    }
}

/// What is at a segment's end point.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum EndKind {
    /// A surface hit by an eye, reflected or transmitted ray.
    Hit,
    /// Nothing: the ray escaped; the end is [`ESCAPE_LENGTH`] along it.
    Escape,
    /// The point light an unblocked shadow ray reaches.
    Light,
    /// An unblocked shadow ray towards a directional light, drawn [`ESCAPE_LENGTH`] long.
    DistantLight,
    /// The nearest surface blocking a shadow ray.
    Occluder,
}

impl EndKind {
    /// The name used in JSON.
    pub fn name(self) -> &'static str {
        match self {
            EndKind::Hit => "hit",
            EndKind::Escape => "escape",
            EndKind::Light => "light",
            EndKind::DistantLight => "distant_light",
            EndKind::Occluder => "occluder",
        }
    }
}

/// One ray of the tree.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    /// Eye, shadow, reflected or transmitted.
    pub kind: SegmentKind,
    /// The segment whose hit spawned this one; `None` only for the eye ray.
    pub parent: Option<SegmentId>,
    /// Where the ray starts (for secondary rays: the parent's end point).
    pub origin: Vec3,
    /// Where the segment ends; see the module doc for the rules.
    pub end: Vec3,
    /// What is at `end`.
    pub end_kind: EndKind,
    /// Bounce depth: 0 for the eye ray, parent + 1 for reflected and transmitted rays; a shadow
    /// ray has its parent's depth.
    pub depth: u32,
    /// The contribution weight the tracer gave the ray (1 for the eye ray; a shadow ray has its
    /// parent's weight).
    pub weight: f32,
    /// Id of the primitive at the end point (hit or occluder), if any; see [`crate::scene::Object`].
    pub prim: Option<u32>,
    /// Material index of that primitive, if any.
    pub material: Option<u32>,
    /// For shadow rays: the index of the light in the scene's light list.
    pub light: Option<u32>,
    /// For shadow rays: whether a surface lies between the point and the light.
    pub blocked: bool,
}

/// The end point of a non-shadow ray that found `hit` (or nothing).
pub fn ray_end(ray: &Ray, hit: Option<&Hit>) -> (Vec3, EndKind) {
    match hit {
        Some(h) => (ray.at(h.t), EndKind::Hit),
        None => (
            ray.origin + ray.dir.normalize() * ESCAPE_LENGTH,
            EndKind::Escape,
        ),
    }
}

/// The end point of a shadow ray towards a light `max_t` away (infinite for a directional
/// light) whose nearest occluder is `occluder`.
pub fn shadow_end(ray: &Ray, max_t: f32, occluder: Option<&Hit>) -> (Vec3, EndKind) {
    match occluder {
        Some(h) => (ray.at(h.t), EndKind::Occluder),
        None if max_t.is_finite() => (ray.at(max_t), EndKind::Light),
        None => (
            ray.origin + ray.dir.normalize() * ESCAPE_LENGTH,
            EndKind::DistantLight,
        ),
    }
}

/// Where a [`RayTree`] came from, for the JSON header.
#[derive(Clone, Copy, Debug)]
pub struct TreeSource<'a> {
    /// The scene file, as given on the command line.
    pub scene: &'a str,
    /// The tracer that recorded the tree (`reference` or `packet`).
    pub tracer: &'a str,
    /// The pixel, x from the left and y from the top.
    pub pixel: [u32; 2],
    /// The image size the pixel belongs to.
    pub image_size: [u32; 2],
}

/// The rays of one pixel: a flat list with parent links, in the order they were recorded.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RayTree {
    /// The segments; a parent always comes before its children.
    pub segments: Vec<Segment>,
}

impl RayTree {
    /// An empty tree.
    pub fn new() -> RayTree {
        RayTree::default()
    }

    /// Records an eye, reflected or transmitted ray with the closest hit it found (`None`: it
    /// escaped). `parent` is the segment whose hit spawned it (`None` for the eye ray); `depth`
    /// and `weight` are the tracer's. Returns the new segment's id, to pass as the parent of
    /// the rays spawned from its hit.
    pub fn add_ray(
        &mut self,
        kind: SegmentKind,
        parent: Option<SegmentId>,
        ray: &Ray,
        hit: Option<Hit>,
        depth: u32,
        weight: f32,
    ) -> SegmentId {
        debug_assert!(
            kind != SegmentKind::Shadow,
            "shadow rays go through add_shadow"
        );
        debug_assert!(parent.is_none_or(|p| p < self.segments.len()));
        let (end, end_kind) = ray_end(ray, hit.as_ref());
        self.segments.push(Segment {
            kind,
            parent,
            origin: ray.origin,
            end,
            end_kind,
            depth,
            weight,
            prim: hit.map(|h| h.prim),
            material: hit.map(|h| h.material),
            light: None,
            blocked: false,
        });
        self.segments.len() - 1
    }

    /// Records the shadow ray from the hit of segment `parent` towards light number `light`,
    /// `max_t` away along `ray` (infinite for a directional light). `occluder` is the nearest
    /// surface in `(EPSILON, max_t)`, `None` if the light is visible. Depth and weight are the
    /// parent's. Returns the new segment's id.
    pub fn add_shadow(
        &mut self,
        parent: SegmentId,
        light: u32,
        ray: &Ray,
        max_t: f32,
        occluder: Option<Hit>,
    ) -> SegmentId {
        let p = &self.segments[parent];
        let (depth, weight) = (p.depth, p.weight);
        let (end, end_kind) = shadow_end(ray, max_t, occluder.as_ref());
        self.segments.push(Segment {
            kind: SegmentKind::Shadow,
            parent: Some(parent),
            origin: ray.origin,
            end,
            end_kind,
            depth,
            weight,
            prim: occluder.map(|h| h.prim),
            material: occluder.map(|h| h.material),
            light: Some(light),
            blocked: occluder.is_some(),
        });
        self.segments.len() - 1
    }

    /// The number of segments of each kind, indexed by [`SegmentKind::index`].
    pub fn kind_counts(&self) -> [usize; 4] {
        let mut n = [0; 4];
        for s in &self.segments {
            n[s.kind.index()] += 1;
        }
        n
    }

    /// The ids of the children of segment `id`.
    pub fn children(&self, id: SegmentId) -> impl Iterator<Item = SegmentId> + '_ {
        (0..self.segments.len()).filter(move |&i| self.segments[i].parent == Some(id))
    }

    /// The same tree in canonical order: sorted by depth, then by the path from the root, where
    /// each step is keyed by (kind, light). Siblings never share that key (a hit spawns at most
    /// one shadow ray per light, one reflected and one transmitted ray), so the order depends
    /// only on the tree's shape, never on floating-point values or on the recording order.
    /// Parent links are remapped; parents still precede their children.
    pub fn canonical(&self) -> RayTree {
        let n = self.segments.len();
        let mut paths: Vec<Vec<(SegmentKind, u32)>> = Vec::with_capacity(n);
        for s in &self.segments {
            // A valid recording adds parents first, so the parent's path is already known;
            // a forward or dangling link is treated as a root rather than panicking.
            let mut path = match s.parent {
                Some(p) if p < paths.len() => paths[p].clone(),
                _ => Vec::new(),
            };
            path.push((s.kind, s.light.unwrap_or(u32::MAX)));
            paths.push(path);
        }
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by(|&a, &b| {
            (self.segments[a].depth, &paths[a]).cmp(&(self.segments[b].depth, &paths[b]))
        });
        let mut new_index = vec![0; n];
        for (new, &old) in order.iter().enumerate() {
            new_index[old] = new;
        }
        let segments = order
            .iter()
            .map(|&old| {
                let mut s = self.segments[old];
                s.parent = s.parent.filter(|&p| p < n).map(|p| new_index[p]);
                s
            })
            .collect();
        RayTree { segments }
    }

    /// The first difference between the canonical forms of `self` and `other`, described for a
    /// test failure; `None` when they agree. Points and weights agree within `tol`, relative to
    /// their size beyond 1 (so escape points [`ESCAPE_LENGTH`] away get a proportional
    /// tolerance); everything else must be equal.
    pub fn first_difference(&self, other: &RayTree, tol: f32) -> Option<String> {
        let (a, b) = (self.canonical(), other.canonical());
        if a.segments.len() != b.segments.len() {
            return Some(format!(
                "{} segments {:?} vs {} segments {:?} (eye, shadow, reflected, transmitted)",
                a.segments.len(),
                a.kind_counts(),
                b.segments.len(),
                b.kind_counts()
            ));
        }
        let close = |x: f32, y: f32| (x - y).abs() <= tol * x.abs().max(y.abs()).max(1.0);
        let close3 = |x: Vec3, y: Vec3| close(x.x, y.x) && close(x.y, y.y) && close(x.z, y.z);
        for (i, (s, t)) in a.segments.iter().zip(&b.segments).enumerate() {
            let same = s.kind == t.kind
                && s.parent == t.parent
                && s.end_kind == t.end_kind
                && s.depth == t.depth
                && s.prim == t.prim
                && s.material == t.material
                && s.light == t.light
                && s.blocked == t.blocked
                && close(s.weight, t.weight)
                && close3(s.origin, t.origin)
                && close3(s.end, t.end);
            if !same {
                return Some(format!("canonical segment {i} differs:\n  {s:?}\n  {t:?}"));
            }
        }
        None
    }

    /// True when the canonical forms of the two trees agree within `tol` (see
    /// [`RayTree::first_difference`]); the recording order does not matter.
    pub fn approx_eq(&self, other: &RayTree, tol: f32) -> bool {
        self.first_difference(other, tol).is_none()
    }

    /// Checks the invariants every recording must satisfy: parents come first; only the eye ray
    /// is a root, at depth 0 with weight 1; children start where their parent ends (within
    /// `1e-4` relative) and only hits have children; depths follow the kinds; end kinds agree
    /// with the hit, light and blocked fields; every number is finite.
    pub fn validate(&self) -> Result<()> {
        let fail =
            |i: usize, msg: String| Err(Error::Other(format!("ray tree segment {i}: {msg}")));
        let close =
            |x: Vec3, y: Vec3| (x - y).abs().max_element() <= 1e-4 * x.abs().max_element().max(1.0);
        for (i, s) in self.segments.iter().enumerate() {
            if !(s.origin.is_finite() && s.end.is_finite() && s.weight.is_finite()) {
                return fail(i, format!("non-finite numbers in {s:?}"));
            }
            let hit_end = matches!(s.end_kind, EndKind::Hit | EndKind::Occluder);
            if hit_end != s.prim.is_some() || s.prim.is_some() != s.material.is_some() {
                return fail(
                    i,
                    format!("end kind {:?} disagrees with prim {:?}", s.end_kind, s.prim),
                );
            }
            let shadow = s.kind == SegmentKind::Shadow;
            let shadow_end = matches!(
                s.end_kind,
                EndKind::Light | EndKind::DistantLight | EndKind::Occluder
            );
            if shadow != shadow_end || shadow != s.light.is_some() {
                return fail(
                    i,
                    format!("a {:?} segment ending at {:?}", s.kind, s.end_kind),
                );
            }
            if s.blocked != (s.end_kind == EndKind::Occluder) {
                return fail(
                    i,
                    format!("blocked is {} but it ends at {:?}", s.blocked, s.end_kind),
                );
            }
            let Some(p) = s.parent else {
                if s.kind != SegmentKind::Eye || s.depth != 0 || s.weight != 1.0 {
                    return fail(
                        i,
                        format!("a root must be the eye ray at depth 0, weight 1: {s:?}"),
                    );
                }
                continue;
            };
            if s.kind == SegmentKind::Eye {
                return fail(i, "an eye ray with a parent".to_string());
            }
            if p >= i {
                return fail(i, format!("parent {p} does not come before it"));
            }
            let parent = &self.segments[p];
            if parent.end_kind != EndKind::Hit {
                return fail(
                    i,
                    format!("its parent {p} ends at {:?}, not a hit", parent.end_kind),
                );
            }
            let depth = if shadow {
                parent.depth
            } else {
                parent.depth + 1
            };
            if s.depth != depth {
                return fail(
                    i,
                    format!("depth {} under a parent of depth {}", s.depth, parent.depth),
                );
            }
            if !close(s.origin, parent.end) {
                return fail(
                    i,
                    format!(
                        "starts at {} but its parent {p} ends at {}",
                        s.origin, parent.end
                    ),
                );
            }
        }
        Ok(())
    }

    /// The tree as JSON: a header saying where it came from, then one object per segment (in
    /// recording order, with its `index`). Hand-written: the format is small and fixed.
    pub fn to_json(&self, source: &TreeSource) -> String {
        let mut out = String::with_capacity(200 + 260 * self.segments.len());
        out.push_str("{\n");
        let _ = writeln!(out, "  \"format\": \"whitted ray tree 1\",");
        let _ = writeln!(out, "  \"scene\": {},", json_string(source.scene));
        let _ = writeln!(out, "  \"tracer\": {},", json_string(source.tracer));
        let _ = writeln!(
            out,
            "  \"pixel\": [{}, {}],",
            source.pixel[0], source.pixel[1]
        );
        let _ = writeln!(
            out,
            "  \"image_size\": [{}, {}],",
            source.image_size[0], source.image_size[1]
        );
        let _ = writeln!(out, "  \"escape_length\": {},", json_number(ESCAPE_LENGTH));
        let counts = self.kind_counts();
        let _ = writeln!(
            out,
            "  \"counts\": {{\"eye\": {}, \"shadow\": {}, \"reflected\": {}, \"transmitted\": {}}},",
            counts[0], counts[1], counts[2], counts[3]
        );
        out.push_str("  \"segments\": [");
        for (i, s) in self.segments.iter().enumerate() {
            out.push_str(if i == 0 { "\n" } else { ",\n" });
            let _ = write!(
                out,
                "    {{\"index\": {i}, \"parent\": {}, \"kind\": \"{}\", \"depth\": {}, \
                 \"weight\": {}, \"origin\": {}, \"end\": {}, \"end_kind\": \"{}\", \
                 \"prim\": {}, \"material\": {}, \"light\": {}, \"blocked\": {}}}",
                json_opt(s.parent),
                s.kind.name(),
                s.depth,
                json_number(s.weight),
                json_vec(s.origin),
                json_vec(s.end),
                s.end_kind.name(),
                json_opt(s.prim),
                json_opt(s.material),
                json_opt(s.light),
                s.blocked
            );
        }
        out.push_str(if self.segments.is_empty() {
            "]\n}\n"
        } else {
            "\n  ]\n}\n"
        });
        out
    }
}

/// A JSON number; non-finite values (which a valid tree never holds) become `null`.
fn json_number(v: f32) -> String {
    if v.is_finite() {
        // Rust prints the shortest digits that read back to the same f32, never in exponent
        // form, which is valid JSON.
        format!("{v}")
    } else {
        "null".to_string()
    }
}

fn json_vec(v: Vec3) -> String {
    format!(
        "[{}, {}, {}]",
        json_number(v.x),
        json_number(v.y),
        json_number(v.z)
    )
}

fn json_opt<T: std::fmt::Display>(v: Option<T>) -> String {
    v.map_or_else(|| "null".to_string(), |v| v.to_string())
}

/// A JSON string literal with the required escapes.
fn json_string(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            c if (c as u32) < 0x20 => {
                let _ = write!(out, "\\u{:04x}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hit(t: f32, prim: u32) -> Option<Hit> {
        Some(Hit {
            t,
            normal: Vec3::Z,
            shading: Vec3::Z,
            material: prim * 10,
            prim,
        })
    }

    #[test]
    fn shadow_rays_end_at_the_light_the_occluder_or_far_away() {
        let ray = Ray::new(Vec3::ZERO, Vec3::X);
        assert_eq!(
            shadow_end(&ray, 3.0, None),
            (Vec3::new(3.0, 0.0, 0.0), EndKind::Light)
        );
        assert_eq!(
            shadow_end(&ray, 3.0, hit(1.0, 4).as_ref()),
            (Vec3::X, EndKind::Occluder)
        );
        assert_eq!(
            shadow_end(&ray, f32::INFINITY, None),
            (Vec3::X * ESCAPE_LENGTH, EndKind::DistantLight)
        );
        let slanted = Ray::new(Vec3::ZERO, Vec3::new(0.0, 2.0, 0.0));
        assert_eq!(ray_end(&slanted, None).0, Vec3::Y * ESCAPE_LENGTH);
    }

    #[test]
    fn json_strings_are_escaped() {
        assert_eq!(json_string("a\"b\\c\n\u{1}"), "\"a\\\"b\\\\c\\n\\u0001\"");
        assert_eq!(json_number(f32::NAN), "null");
        assert_eq!(json_number(1e-7), "0.0000001");
    }

    #[test]
    fn an_eye_ray_with_two_shadow_rays_validates() {
        let mut t = RayTree::new();
        let eye = Ray::new(Vec3::ZERO, -Vec3::Z);
        let e = t.add_ray(SegmentKind::Eye, None, &eye, hit(2.0, 1), 0, 1.0);
        let p = Vec3::new(0.0, 0.0, -2.0);
        t.add_shadow(e, 1, &Ray::new(p, Vec3::Y), 5.0, None);
        t.add_shadow(e, 0, &Ray::new(p, Vec3::X), f32::INFINITY, hit(0.5, 2));
        t.validate().unwrap();
        let c = t.canonical();
        assert_eq!(c.segments[1].light, Some(0));
        assert!(c.segments[1].blocked);
        assert_eq!(c.segments[2].end, p + Vec3::Y * 5.0);
        assert!(t.approx_eq(&c, 0.0));
    }
}
