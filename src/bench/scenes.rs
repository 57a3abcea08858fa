//! The four procedural scenes of `../shared/bench/SCENES.md`: a ground quad plus a grid of
//! analytic spheres or a UV torus mesh. [`BenchScene::geometry`] builds their primitives, the
//! first step of `whitted bench` (`rays.rs` then makes the rays, `kernels.rs` traces them).

use std::f32::consts::PI;

use crate::geometry::Geometry;
use crate::math::Vec3;

/// One of the four procedural scenes of the contract.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BenchScene {
    /// 8 x 8 analytic spheres on the ground quad.
    Spheres64,
    /// 64 x 64 analytic spheres on the ground quad.
    Spheres4096,
    /// A 250 x 200 UV torus (100,000 triangles) on the ground quad.
    Torus100k,
    /// A 1000 x 500 UV torus (1,000,000 triangles) on the ground quad.
    Torus1m,
}

impl BenchScene {
    /// Every scene, in the order the Embree harness runs them.
    pub const ALL: [BenchScene; 4] = [
        BenchScene::Spheres64,
        BenchScene::Spheres4096,
        BenchScene::Torus100k,
        BenchScene::Torus1m,
    ];

    /// The scene's name in the CSV rows.
    pub fn name(self) -> &'static str {
        match self {
            BenchScene::Spheres64 => "spheres64",
            BenchScene::Spheres4096 => "spheres4096",
            BenchScene::Torus100k => "torus100k",
            BenchScene::Torus1m => "torus1m",
        }
    }

    /// The scene called `name`.
    pub fn from_name(name: &str) -> Option<BenchScene> {
        BenchScene::ALL.into_iter().find(|s| s.name() == name)
    }

    /// The number of primitives, the 2 ground triangles included.
    pub fn primitive_count(self) -> usize {
        2 + match self.shape() {
            Shape::SphereGrid(g) => g * g,
            Shape::Torus(u, v) => 2 * u * v,
        }
    }

    fn shape(self) -> Shape {
        match self {
            BenchScene::Spheres64 => Shape::SphereGrid(8),
            BenchScene::Spheres4096 => Shape::SphereGrid(64),
            BenchScene::Torus100k => Shape::Torus(250, 200),
            BenchScene::Torus1m => Shape::Torus(1000, 500),
        }
    }

    /// The scene's primitives, without acceleration structure: the ground quad's 2 triangles
    /// first, then the spheres (grid order `i * G + j`) or the torus triangles (quad order).
    pub fn geometry(self) -> Geometry {
        let mut g = Geometry::default();
        push_ground(&mut g);
        match self.shape() {
            Shape::SphereGrid(grid) => push_sphere_grid(&mut g, grid),
            Shape::Torus(u, v) => push_torus(&mut g, u, v),
        }
        g
    }
}

/// What stands on the ground quad.
#[derive(Clone, Copy)]
enum Shape {
    /// G x G spheres.
    SphereGrid(usize),
    /// U segments around the major circle, V around the tube.
    Torus(usize, usize),
}

/// Appends triangle `v` with its unit geometric normal; material 0, scene id = its index.
fn push_triangle(g: &mut Geometry, v: [Vec3; 3]) {
    let n = (v[1] - v[0]).cross(v[2] - v[0]).normalize();
    let id = g.triangles.len() as u32;
    g.triangles.push(v, n, 0, id);
}

/// The ground quad at y = 0, x and z in [-2, 2], as triangles (v0, v1, v2) and (v0, v2, v3).
fn push_ground(g: &mut Geometry) {
    let v = [
        Vec3::new(-2.0, 0.0, -2.0),
        Vec3::new(2.0, 0.0, -2.0),
        Vec3::new(2.0, 0.0, 2.0),
        Vec3::new(-2.0, 0.0, 2.0),
    ];
    push_triangle(g, [v[0], v[1], v[2]]);
    push_triangle(g, [v[0], v[2], v[3]]);
}

/// G x G spheres of radius 0.4 s, s = 2 / G, centred at (-1 + s (i + 0.5), r, -1 + s (j + 0.5)).
fn push_sphere_grid(g: &mut Geometry, grid: usize) {
    let s = 2.0 / grid as f32;
    let r = 0.4 * s;
    for i in 0..grid {
        for j in 0..grid {
            let center = Vec3::new(-1.0 + s * (i as f32 + 0.5), r, -1.0 + s * (j as f32 + 0.5));
            let id = g.spheres.len() as u32;
            g.spheres.push(center, r, 0, id);
        }
    }
}

/// The UV torus of major radius 0.7 and minor radius 0.3 resting on the ground: vertex (i, j)
/// at index i V + j; quad (i, j) as triangles (a, b, c) and (b, d, c).
fn push_torus(g: &mut Geometry, u: usize, v: usize) {
    let (major, minor) = (0.7f32, 0.3f32);
    let mut vertices = Vec::with_capacity(u * v);
    for i in 0..u {
        let theta = 2.0 * PI * i as f32 / u as f32;
        for j in 0..v {
            let phi = 2.0 * PI * j as f32 / v as f32;
            vertices.push(Vec3::new(
                (major + minor * phi.cos()) * theta.cos(),
                minor + minor * phi.sin(),
                (major + minor * phi.cos()) * theta.sin(),
            ));
        }
    }
    for i in 0..u {
        for j in 0..v {
            let (i1, j1) = ((i + 1) % u, (j + 1) % v);
            let a = vertices[i * v + j];
            let b = vertices[i1 * v + j];
            let c = vertices[i * v + j1];
            let d = vertices[i1 * v + j1];
            push_triangle(g, [a, b, c]);
            push_triangle(g, [b, d, c]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scenes_have_the_contract_primitive_counts() {
        for s in BenchScene::ALL {
            let g = s.geometry();
            assert_eq!(g.len(), s.primitive_count(), "{}", s.name());
            assert_eq!(BenchScene::from_name(s.name()), Some(s));
        }
        assert_eq!(BenchScene::Torus100k.primitive_count(), 100_002);
        assert_eq!(BenchScene::Spheres4096.primitive_count(), 4098);
    }
}
