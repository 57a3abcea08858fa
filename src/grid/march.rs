//! The 3D-DDA of assignment 5 (`initializeRayMarch` and `nextCell`): a ray enters the grid's
//! box (ray-box intersection is used only for that), then steps from cell to cell, always across
//! the nearest of the three next cell boundaries, until it finds an occupied cell or leaves the
//! grid. What it reports is what the grid picture draws: the cell, its count, the distance at
//! which the ray entered it and the normal of the face it entered by.
//!
//! ```text
//! slab test against the box -> t_enter (the entry face's axis: the latest slab entry)
//! cell = floor((o + t d - lo) / cell size); t_next per axis; dt = cell size / |d|
//! loop: occupied? -> hit | step along argmin t_next (ties: x, then y, then z) | outside -> miss
//! ```
//!
//! The three cases of the handout: a ray from outside that misses the box; one that enters it
//! (the march starts at the entry point, normal: the face entered); and one that starts inside
//! (at `tmin`, in the cell of its origin). For that last case the handout names no face; whitted
//! reports the face of the origin's cell through which the ray's line, extended backwards,
//! entered that cell (the axis whose cell boundary behind the origin is nearest to it), so a
//! camera inside the grid sees the cells around it shaded like cells seen from outside.

use super::Grid;
use crate::math::{Ray, Vec3};

/// The first occupied cell along a ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridHit {
    /// The cell `(i, j, k)`.
    pub cell: [u32; 3],
    /// How many primitives mark it.
    pub count: u32,
    /// The ray parameter where the ray enters the cell (`tmin` when it starts inside it).
    pub t: f32,
    /// The unit normal of the face the ray entered by, pointing back towards the ray.
    pub normal: Vec3,
}

impl Grid {
    /// Marches `ray` from `tmin` through the grid; the first occupied cell, if any.
    pub fn march(&self, ray: &Ray, tmin: f32) -> Option<GridHit> {
        let (lo, hi) = self.bounds?;
        let (o, d) = (ray.origin.to_array(), ray.dir.to_array());
        let (lo, hi) = (lo.to_array(), hi.to_array());
        let size = self.cell_size.to_array();
        // Slab test: the latest entry and the earliest exit over the three axes.
        let (mut t_enter, mut t_exit, mut entry_axis) = (f32::NEG_INFINITY, f32::INFINITY, 0);
        for a in 0..3 {
            let (t0, t1) = if d[a] == 0.0 {
                if o[a] < lo[a] || o[a] > hi[a] {
                    return None;
                }
                (f32::NEG_INFINITY, f32::INFINITY)
            } else {
                let (ta, tb) = ((lo[a] - o[a]) / d[a], (hi[a] - o[a]) / d[a]);
                (ta.min(tb), ta.max(tb))
            };
            if t0 > t_enter {
                (t_enter, entry_axis) = (t0, a);
            }
            t_exit = t_exit.min(t1);
        }
        if t_enter > t_exit || t_exit < tmin {
            return None;
        }
        let start = t_enter.max(tmin);
        let mut cell = [0i64; 3];
        let mut step = [0i64; 3];
        let mut t_next = [f32::INFINITY; 3];
        let mut dt = [f32::INFINITY; 3];
        for a in 0..3 {
            let n = self.cells[a] as i64;
            let p = o[a] + start * d[a];
            cell[a] = (((p - lo[a]) / size[a]).floor() as i64).clamp(0, n - 1);
            if d[a] != 0.0 {
                step[a] = if d[a] > 0.0 { 1 } else { -1 };
                dt[a] = size[a] / d[a].abs();
                let edge = lo[a] + (cell[a] + (d[a] > 0.0) as i64) as f32 * size[a];
                t_next[a] = (edge - o[a]) / d[a];
            }
        }
        if t_enter < tmin {
            // The origin is inside: the face its line entered the origin's cell by.
            entry_axis = (0..3)
                .filter(|&a| d[a] != 0.0)
                .max_by(|&a, &b| (t_next[a] - dt[a]).total_cmp(&(t_next[b] - dt[b])))
                .unwrap_or(0);
        }
        let mut axis = entry_axis;
        let mut t = start;
        loop {
            let here = cell.map(|c| c as u32);
            let count = self.count(here);
            if count > 0 {
                let mut normal = [0.0f32; 3];
                normal[axis] = if d[axis] > 0.0 { -1.0 } else { 1.0 };
                return Some(GridHit {
                    cell: here,
                    count,
                    t,
                    normal: Vec3::from_array(normal),
                });
            }
            axis = if t_next[0] <= t_next[1] && t_next[0] <= t_next[2] {
                0
            } else if t_next[1] <= t_next[2] {
                1
            } else {
                2
            };
            if t_next[axis] == f32::INFINITY {
                return None;
            }
            t = t_next[axis];
            cell[axis] += step[axis];
            if cell[axis] < 0 || cell[axis] >= self.cells[axis] as i64 {
                return None;
            }
            t_next[axis] += dt[axis];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Scene;
    use std::path::Path;

    /// A grid of `n^3` cells over the box of the given three objects.
    fn grid(objects: &str, n: u32) -> Grid {
        let text = format!(
            "OrthographicCamera {{ center 0 0 10 direction 0 0 -1 up 0 1 0 size 5 }}
             Lights {{ numLights 0 }}
             Background {{ color 0 0 0 }}
             Materials {{ numMaterials 1 PhongMaterial {{ diffuseColor 1 1 1 }} }}
             Group {{ numObjects 3 MaterialIndex 0 {objects} }}"
        );
        Grid::build(&Scene::from_str(&text, Path::new("g.txt")).unwrap(), [n; 3])
    }

    fn corners_and_middle() -> Grid {
        // Three small triangles in a 4x4x4 grid over [0, 4]^3 (unit cells): one in cell
        // (0,0,0), one in (2,1,3), one in the far corner (3,3,3).
        grid(
            "Triangle { vertex0 0 0 0 vertex1 0.5 0 0 vertex2 0 0.5 0 }
             Triangle { vertex0 2.2 1.2 3.2 vertex1 2.8 1.2 3.2 vertex2 2.2 1.8 3.8 }
             Triangle { vertex0 3.6 3.6 3.6 vertex1 4 3.6 4 vertex2 3.6 4 4 }",
            4,
        )
    }

    #[test]
    fn a_ray_from_outside_reports_the_face_it_entered_by() {
        let g = corners_and_middle();
        assert_eq!(g.count([0, 0, 0]), 1);
        assert_eq!(g.count([2, 1, 3]), 1);
        assert_eq!(g.stats().occupied, 3);
        assert_eq!(g.bounds, Some((Vec3::ZERO, Vec3::splat(4.0))));
        // Down the z axis through cell column (2, 1): enters the box at z = 4 (its +z face);
        // the cell (2,1,3) is the first.
        let h = g
            .march(&Ray::new(Vec3::new(2.5, 1.5, 10.0), -Vec3::Z), 0.0)
            .unwrap();
        assert_eq!((h.cell, h.count, h.normal), ([2, 1, 3], 1, Vec3::Z));
        assert!((h.t - 6.0).abs() < 1e-5);
        // Along +x through row (j, k) = (1, 3): crosses cells 0 and 1 first, enters (2,1,3)
        // through its -x face at x = 2.
        let h = g
            .march(&Ray::new(Vec3::new(-5.0, 1.5, 3.5), Vec3::X), 0.0)
            .unwrap();
        assert_eq!((h.cell, h.normal), ([2, 1, 3], -Vec3::X));
        assert!((h.t - 7.0).abs() < 1e-5);
        // A ray that misses the box, and one that crosses only empty cells.
        assert_eq!(
            g.march(&Ray::new(Vec3::new(-5.0, 9.0, 3.5), Vec3::X), 0.0),
            None
        );
        assert_eq!(
            g.march(&Ray::new(Vec3::new(-5.0, 2.5, 3.5), Vec3::X), 0.0),
            None
        );
        // Behind tmin: the box is behind the ray.
        assert_eq!(
            g.march(&Ray::new(Vec3::new(9.0, 1.5, 3.5), Vec3::X), 0.0),
            None
        );
    }

    #[test]
    fn a_ray_starting_inside_begins_in_its_own_cell() {
        let g = corners_and_middle();
        // Starting inside the occupied cell (2,1,3), going mostly +y: its line entered the
        // cell through the -y face.
        let ray = Ray::new(
            Vec3::new(2.5, 1.3, 3.5),
            Vec3::new(0.1, 1.0, 0.05).normalize(),
        );
        let h = g.march(&ray, 0.0).unwrap();
        assert_eq!((h.cell, h.t, h.normal), ([2, 1, 3], 0.0, -Vec3::Y));
        // Starting in an empty cell and marching diagonally into (0,0,0).
        let ray = Ray::new(Vec3::new(1.5, 1.5, 1.5), Vec3::splat(-1.0).normalize());
        let h = g.march(&ray, 0.0).unwrap();
        assert_eq!(h.cell, [0, 0, 0]);
    }

    #[test]
    fn rays_along_an_axis_and_through_cell_corners_do_not_get_lost() {
        let g = corners_and_middle();
        // Exactly along a cell boundary plane (x = 2) with zero x and y direction components.
        let h = g
            .march(&Ray::new(Vec3::new(2.0, 1.5, -3.0), Vec3::Z), 0.0)
            .unwrap();
        assert_eq!(h.cell, [2, 1, 3]);
        assert_eq!(h.normal, -Vec3::Z);
        // A ray parallel to an axis outside the box's slab misses.
        assert_eq!(
            g.march(&Ray::new(Vec3::new(4.5, 1.5, -3.0), Vec3::Z), 0.0),
            None
        );
    }
}
