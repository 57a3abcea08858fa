//! The ray tree of one pixel, the lecture's debugging tool: every ray spawned for the pixel, by
//! kind (eye, shadow, reflected, transmitted), with its origin and end point. The tracers record
//! into a [`RayTree`] when asked; the CLI writes it as JSON.

use crate::math::{Ray, Vec3};
use crate::shade::Hit;

/// Where a segment ends when its ray escapes the scene (distance along the unit direction).
pub const ESCAPE_LENGTH: f32 = 100.0;

/// The kind of a ray; the course draws eye rays gray, shadow rays green, reflected red,
/// transmitted blue.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum SegmentKind {
    Eye,
    Shadow,
    Reflected,
    Transmitted,
}

impl SegmentKind {
    /// The name used in JSON.
    pub fn name(self) -> &'static str {
        match self {
            SegmentKind::Eye => "eye",
            SegmentKind::Shadow => "shadow",
            SegmentKind::Reflected => "reflected",
            SegmentKind::Transmitted => "transmitted",
        }
    }
}

/// One ray of the tree.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    pub kind: SegmentKind,
    /// Index of the ray that spawned this one.
    pub parent: Option<usize>,
    pub origin: Vec3,
    /// Hit point, light position, or `origin + ESCAPE_LENGTH * dir` for an escaping ray.
    pub end: Vec3,
    /// Bounce depth (0 for the eye ray and its shadow rays).
    pub depth: u32,
    pub weight: f32,
    /// Id of the primitive hit (see [`crate::scene::Object`]), if any.
    pub prim: Option<u32>,
    /// Material index of the surface hit, if any.
    pub material: Option<u32>,
    /// For shadow rays: whether something blocked the light.
    pub blocked: bool,
}

/// The rays of one pixel, in the order they were traced.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RayTree {
    pub segments: Vec<Segment>,
}

impl RayTree {
    /// Records a traced ray and what it hit; returns its index.
    pub fn add_ray(
        &mut self,
        kind: SegmentKind,
        parent: Option<usize>,
        ray: &Ray,
        hit: Option<Hit>,
        depth: u32,
        weight: f32,
    ) -> usize {
        let end = match hit {
            Some(h) => ray.at(h.t),
            None => ray.origin + ray.dir.normalize() * ESCAPE_LENGTH,
        };
        self.segments.push(Segment {
            kind,
            parent,
            origin: ray.origin,
            end,
            depth,
            weight,
            prim: hit.map(|h| h.prim),
            material: hit.map(|h| h.material),
            blocked: false,
        });
        self.segments.len() - 1
    }

    /// Records the shadow ray of ray `parent` towards a light `max_t` away.
    pub fn add_shadow(&mut self, parent: usize, ray: &Ray, max_t: f32, blocked: bool) {
        let length = if max_t.is_finite() {
            max_t
        } else {
            ESCAPE_LENGTH
        };
        let p = &self.segments[parent];
        let (depth, weight) = (p.depth, p.weight);
        self.segments.push(Segment {
            kind: SegmentKind::Shadow,
            parent: Some(parent),
            origin: ray.origin,
            end: ray.at(length),
            depth,
            weight,
            prim: None,
            material: None,
            blocked,
        });
    }
}
