//! The scene as the course's file describes it: a camera, lights, a background, a material table
//! and a tree of objects (groups, transforms and primitives). [`Scene::load`] parses a file
//! (see [`parse`] for the grammar, `docs/scene-format.md` for users); the reference tracer walks
//! the tree as it is, the packet tracer flattens it into world-space SoA arrays first.
//!
//! ```text
//! file --input--> text --token--> tokens --cursor--> parse (+ blocks, obj) --passes-->
//!      Scene { camera, lights, materials, root: Object tree }
//!                  |-> reference tracer (recursive, walks the tree)
//!                  '-> flatten -> SoA primitives -> packet tracer
//! ```

mod blocks;
pub mod camera;
mod cursor;
mod input;
pub mod normals;
pub mod obj;
mod obj_lines;
pub mod parse;
mod passes;
pub mod texture;
mod token;

use std::path::Path;

use crate::error::Result;
use crate::math::{Mat3, Mat4, Vec3};
pub use camera::{Camera, Projection};
pub use texture::{Texture, TextureKind};

/// A parsed scene, ready to render.
#[derive(Clone, Debug)]
pub struct Scene {
    pub camera: Camera,
    pub lights: Vec<Light>,
    pub background: Vec3,
    pub ambient: Vec3,
    pub materials: Vec<Material>,
    pub root: Object,
}

impl Scene {
    /// Reads and parses the scene file at `path` (OBJ meshes are loaded relative to it).
    pub fn load(path: &Path) -> Result<Scene> {
        parse::parse_file(path)
    }

    /// Parses scene text; `path` names it in error messages and anchors relative OBJ paths.
    pub fn from_str(text: &str, path: &Path) -> Result<Scene> {
        parse::parse_str(text, path)
    }

    /// The number of primitives (triangles of meshes counted one by one).
    pub fn primitive_count(&self) -> usize {
        self.root.primitive_count()
    }
}

/// A light source.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Light {
    /// Parallel light arriving along `direction` (unit); the direction to the light is its
    /// opposite and the light is infinitely far.
    Directional { direction: Vec3, color: Vec3 },
    /// A point light; its colour is divided by `c + l d + q d^2` at distance `d`.
    Point {
        position: Vec3,
        color: Vec3,
        attenuation: [f32; 3],
    },
}

/// What a light gives a point: unit direction towards the light, colour arriving, distance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Illumination {
    pub dir: Vec3,
    pub color: Vec3,
    pub distance: f32,
}

impl Light {
    /// The light arriving at `p`.
    pub fn illuminate(&self, p: Vec3) -> Illumination {
        // One `Illumination` built after the match: built in each arm, it went through the
        // stack, and its first use waited on the stores (PERF.md, sitting 37)
        let (dir, color, distance) = match *self {
            Light::Directional { direction, color } => (-direction, color, f32::INFINITY),
            Light::Point {
                position,
                color,
                attenuation: [c, l, q],
            } => {
                let to_light = position - p;
                let distance = to_light.length();
                let denom = c + l * distance + q * distance * distance;
                let color = if denom > 0.0 {
                    crate::math::saturate(color / denom)
                } else {
                    Vec3::ZERO
                };
                (to_light.normalize_or_zero(), color, distance)
            }
        };
        Illumination {
            dir,
            color,
            distance,
        }
    }
}

/// The Phong material of the course (all colours linear RGB).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Phong {
    pub diffuse: Vec3,
    pub specular: Vec3,
    pub exponent: f32,
    pub reflective: Vec3,
    pub transparent: Vec3,
    pub ior: f32,
}

impl Default for Phong {
    /// The course defaults: white diffuse, no specular, exponent 1, no mirror, opaque, index 1.
    fn default() -> Phong {
        Phong {
            diffuse: Vec3::ONE,
            specular: Vec3::ZERO,
            exponent: 1.0,
            reflective: Vec3::ZERO,
            transparent: Vec3::ZERO,
            ior: 1.0,
        }
    }
}

/// A material: plain Phong, or a solid texture choosing between two other materials (see
/// [`texture`]); [`Scene::phong_at`] resolves either to Phong parameters at a point.
#[derive(Clone, Debug, PartialEq)]
pub enum Material {
    Phong(Phong),
    Texture(Texture),
}

/// A node of the object tree. Primitives carry the index of their material and an `id`: their
/// position in the file, counting every primitive (each mesh triangle too) depth first from 0.
/// Both tracers report hits by this id.
#[derive(Clone, Debug, PartialEq)]
pub enum Object {
    Sphere {
        center: Vec3,
        radius: f32,
        material: u32,
        id: u32,
    },
    /// Points `p` with `normal . p = offset`; `normal` is unit length.
    Plane {
        normal: Vec3,
        offset: f32,
        material: u32,
        id: u32,
    },
    /// Counter-clockwise vertices face the viewer.
    Triangle {
        v: [Vec3; 3],
        material: u32,
        id: u32,
    },
    /// An OBJ mesh: its triangles, all of one material; triangle `k` has id `first_id + k`.
    Mesh {
        triangles: Vec<[Vec3; 3]>,
        /// Unit corner normals of each triangle for smooth shading (see [`normals`]), parallel
        /// to `triangles`; empty for a flat mesh.
        normals: Vec<[Vec3; 3]>,
        material: u32,
        first_id: u32,
    },
    Group(Vec<Object>),
    Transform(Box<Transformed>),
}

/// An object under an affine transform, with the matrices the intersection needs precomputed.
#[derive(Clone, Debug, PartialEq)]
pub struct Transformed {
    /// Object to world.
    pub matrix: Mat4,
    /// World to object.
    pub inverse: Mat4,
    /// The inverse transpose, for normals.
    pub normal_matrix: Mat3,
    pub child: Object,
}

impl Transformed {
    /// `child` under `matrix`, which must be invertible (the parser checks).
    pub fn new(matrix: Mat4, child: Object) -> Transformed {
        let inverse = matrix.inverse();
        Transformed {
            matrix,
            inverse,
            normal_matrix: Mat3::from_mat4(inverse.transpose()),
            child,
        }
    }
}

impl Object {
    /// The number of primitives below this node.
    pub fn primitive_count(&self) -> usize {
        match self {
            Object::Sphere { .. } | Object::Plane { .. } | Object::Triangle { .. } => 1,
            Object::Mesh { triangles, .. } => triangles.len(),
            Object::Group(children) => children.iter().map(Object::primitive_count).sum(),
            Object::Transform(t) => t.child.primitive_count(),
        }
    }
}
