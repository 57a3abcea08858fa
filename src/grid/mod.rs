//! The course's uniform grid (assignments 5 and 6): the box of the scene's bounded primitives
//! cut into `nx x ny x nz` cells, each cell counting the primitives that may overlap it.
//! whitted renders with its BVH; the grid exists for `-grid NX NY NZ` (its size and occupancy
//! in `--stats`) and for the picture of its occupancy, `-visualize_grid` ([`march`] walks a ray
//! through the cells, [`picture`] colours the first occupied one). Both tracers call the same
//! scalar march, so they draw the same picture.
//!
//! ```text
//! Scene.root (tree) --Grid::build--> Grid { box, cell counts }
//!                                      |-> GridStats (--stats)
//!                                      '-> march(ray) -> GridHit -> picture::pixel (both tracers)
//! ```
//!
//! Which cells a primitive marks, as the handouts say (planes are infinite: never inserted, not
//! part of the box):
//!
//! - a triangle (each mesh triangle too) marks the cells of the box of its three vertices, taken
//!   after its transforms (the handout's "special case for transformed triangles", which the
//!   instructor's images use);
//! - a sphere that is under no `Transform` marks the cells whose centre lies within its radius of
//!   its centre (the handout's rule);
//! - a sphere under any `Transform`, even an identity one, marks the cells of the box of its 8
//!   transformed box corners (the course's fallback when the matrix is not NULL).
//!
//! The cells of a box `[a, b]` are those from `floor((a - e - lo) / d)` to
//! `floor((b + e - lo) / d)` on each axis, clamped to the grid, with `d` the cell size and
//! `e = 1e-4 d`: a box face lying on a cell boundary marks the cells on both sides, whatever the
//! rounding (the instructor's counts on output5_12 need this). The grid's box is the union of the
//! primitives' boxes; an axis of zero extent (a single flat triangle) is padded to a thickness
//! of 1e-3 of the largest extent (1 if all are zero), centred on it.

pub mod march;
pub mod picture;

use crate::math::{Mat4, Vec3};
use crate::scene::{Object, Scene};
use crate::stats::GridStats;

pub use march::GridHit;

/// How far beyond a box, in cells, its marking reaches (see the module docs).
const MARGIN: f32 = 1e-4;

/// A uniform grid over the scene's bounded primitives, with the number of primitives marking
/// each cell.
#[derive(Clone, Debug, PartialEq)]
pub struct Grid {
    /// Cells per axis.
    pub cells: [u32; 3],
    /// The grid's box; `None` when the scene has no bounded primitive (then no cell is
    /// occupied and every ray misses).
    pub bounds: Option<(Vec3, Vec3)>,
    /// The size of one cell.
    pub cell_size: Vec3,
    /// Primitives per cell, `x` fastest, then `y`, then `z`.
    counts: Vec<u32>,
}

/// One primitive as the grid marks it.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Footprint {
    /// The cells of a box.
    Box(Vec3, Vec3),
    /// The cells whose centre lies within `radius` of `center`.
    Sphere { center: Vec3, radius: f32 },
}

impl Footprint {
    fn bounds(&self) -> (Vec3, Vec3) {
        match *self {
            Footprint::Box(lo, hi) => (lo, hi),
            Footprint::Sphere { center, radius } => {
                (center - Vec3::splat(radius), center + Vec3::splat(radius))
            }
        }
    }
}

impl Grid {
    /// Builds the grid of `scene` with `cells` cells per axis (at least 1 each, and few
    /// enough to allocate: `options::check_options` checks both).
    pub fn build(scene: &Scene, cells: [u32; 3]) -> Grid {
        let mut prims = Vec::new();
        footprints(&scene.root, &Mat4::IDENTITY, false, &mut prims);
        let total = cells.iter().map(|&n| n as usize).product::<usize>();
        let mut grid = Grid {
            cells,
            bounds: None,
            cell_size: Vec3::ZERO,
            counts: vec![0; total],
        };
        let Some((lo, hi)) = prims
            .iter()
            .map(Footprint::bounds)
            .reduce(|a, b| (a.0.min(b.0), a.1.max(b.1)))
        else {
            return grid;
        };
        let (lo, hi) = pad_flat_axes(lo, hi);
        let n = Vec3::new(cells[0] as f32, cells[1] as f32, cells[2] as f32);
        grid.bounds = Some((lo, hi));
        grid.cell_size = (hi - lo) / n;
        for p in &prims {
            grid.mark(p);
        }
        grid
    }

    /// The number of primitives marking cell `(i, j, k)`.
    pub fn count(&self, cell: [u32; 3]) -> u32 {
        self.counts[self.index(cell)]
    }

    fn index(&self, [i, j, k]: [u32; 3]) -> usize {
        let [nx, ny, _] = self.cells.map(|n| n as usize);
        i as usize + nx * (j as usize + ny * k as usize)
    }

    /// The centre of cell `(i, j, k)` (the grid must have a box).
    pub fn cell_center(&self, cell: [u32; 3]) -> Vec3 {
        let (lo, _) = self.bounds.expect("a grid with a box");
        let c = Vec3::new(cell[0] as f32, cell[1] as f32, cell[2] as f32);
        lo + (c + Vec3::splat(0.5)) * self.cell_size
    }

    /// The cells `[first, last]` (inclusive, per axis) the box `[a, b]` marks.
    fn cell_range(&self, a: Vec3, b: Vec3) -> ([u32; 3], [u32; 3]) {
        let (lo, _) = self.bounds.expect("a grid with a box");
        let d = self.cell_size;
        let e = d * MARGIN;
        let first = ((a - e - lo) / d).floor();
        let last = ((b + e - lo) / d).floor();
        let clamp = |v: f32, axis: usize| v.clamp(0.0, (self.cells[axis] - 1) as f32) as u32;
        (
            [clamp(first.x, 0), clamp(first.y, 1), clamp(first.z, 2)],
            [clamp(last.x, 0), clamp(last.y, 1), clamp(last.z, 2)],
        )
    }

    fn mark(&mut self, p: &Footprint) {
        let (a, b) = p.bounds();
        let (first, last) = self.cell_range(a, b);
        for k in first[2]..=last[2] {
            for j in first[1]..=last[1] {
                for i in first[0]..=last[0] {
                    let inside = match *p {
                        Footprint::Box(..) => true,
                        Footprint::Sphere { center, radius } => {
                            (self.cell_center([i, j, k]) - center).length_squared()
                                <= radius * radius
                        }
                    };
                    if inside {
                        let at = self.index([i, j, k]);
                        self.counts[at] += 1;
                    }
                }
            }
        }
    }

    /// Size, box and occupancy, for `--stats` (the build time is the caller's to fill in).
    pub fn stats(&self) -> GridStats {
        let occupied: Vec<u32> = self.counts.iter().copied().filter(|&c| c > 0).collect();
        GridStats {
            cells: self.cells,
            bounds: self.bounds.map(|(lo, hi)| (lo.to_array(), hi.to_array())),
            occupied: occupied.len() as u64,
            max_count: occupied.iter().copied().max().unwrap_or(0),
            marks: occupied.iter().map(|&c| c as u64).sum(),
            build: std::time::Duration::ZERO,
        }
    }
}

/// Pads axes of zero extent (see the module docs).
fn pad_flat_axes(lo: Vec3, hi: Vec3) -> (Vec3, Vec3) {
    let extent = hi - lo;
    let largest = extent.max_element();
    let thickness = if largest > 0.0 { 1e-3 * largest } else { 1.0 };
    let pad = Vec3::select(
        extent.cmple(Vec3::ZERO),
        Vec3::splat(0.5 * thickness),
        Vec3::ZERO,
    );
    (lo - pad, hi + pad)
}

/// Collects the footprint of every bounded primitive below `obj`, which sits under the
/// object-to-world matrix `m`; `transformed` is true below any `Transform` node.
fn footprints(obj: &Object, m: &Mat4, transformed: bool, out: &mut Vec<Footprint>) {
    let box_of = |points: &mut dyn Iterator<Item = Vec3>| {
        let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        for p in points {
            let p = m.transform_point3(p);
            lo = lo.min(p);
            hi = hi.max(p);
        }
        Footprint::Box(lo, hi)
    };
    match obj {
        Object::Sphere { center, radius, .. } => {
            if transformed {
                let r = Vec3::splat(*radius);
                let (lo, hi) = (*center - r, *center + r);
                out.push(box_of(&mut (0..8).map(|c| {
                    Vec3::select(glam::BVec3::new(c & 1 != 0, c & 2 != 0, c & 4 != 0), hi, lo)
                })));
            } else {
                out.push(Footprint::Sphere {
                    center: *center,
                    radius: *radius,
                });
            }
        }
        Object::Plane { .. } => {}
        Object::Triangle { v, .. } => out.push(box_of(&mut v.iter().copied())),
        Object::Mesh { triangles, .. } => {
            for v in triangles {
                out.push(box_of(&mut v.iter().copied()));
            }
        }
        Object::Group(children) => {
            for c in children {
                footprints(c, m, transformed, out);
            }
        }
        Object::Transform(t) => footprints(&t.child, &(*m * t.matrix), true, out),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn scene(objects: &str) -> Scene {
        let text = format!(
            "OrthographicCamera {{ center 0 0 10 direction 0 0 -1 up 0 1 0 size 5 }}
             Lights {{ numLights 0 }}
             Background {{ color 0 0 0 }}
             Materials {{ numMaterials 1 PhongMaterial {{ diffuseColor 1 1 1 }} }}
             Group {{ numObjects 1 MaterialIndex 0 {objects} }}"
        );
        Scene::from_str(&text, Path::new("grid.txt")).unwrap()
    }

    fn occupied(g: &Grid) -> Vec<[u32; 3]> {
        let mut out = Vec::new();
        for k in 0..g.cells[2] {
            for j in 0..g.cells[1] {
                for i in 0..g.cells[0] {
                    if g.count([i, j, k]) > 0 {
                        out.push([i, j, k]);
                    }
                }
            }
        }
        out
    }

    #[test]
    fn flat_axes_are_padded() {
        let g = Grid::build(
            &scene("Triangle { vertex0 0 0 0 vertex1 2 0 0 vertex2 0 1 0 }"),
            [2, 2, 2],
        );
        let (lo, hi) = g.bounds.unwrap();
        assert_eq!((lo.x, hi.x, lo.y, hi.y), (0.0, 2.0, 0.0, 1.0));
        assert!((hi.z - lo.z - 2e-3).abs() < 1e-7 && lo.z < 0.0 && hi.z > 0.0);
        assert_eq!(occupied(&g).len(), 8);
    }

    #[test]
    fn a_scene_without_bounded_primitives_has_no_box() {
        let g = Grid::build(&scene("Plane { normal 0 1 0 offset 0 }"), [3, 3, 3]);
        assert_eq!(g.bounds, None);
        assert_eq!(g.stats().occupied, 0);
    }
}
