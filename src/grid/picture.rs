//! The grid picture (`-visualize_grid`, `-visualize_grid_count`): what one camera ray shows
//! when it is marched through the grid instead of traced through the scene. Both tracers call
//! [`pixel`] for every camera ray, so they draw the same picture.
//!
//! The first occupied cell is drawn in the colour of its count on a ramp (the one read off the
//! instructor's output5_12 and output6_18b, byte for byte):
//!
//! ```text
//! count   1      2      3       4       5      6       7       8      9       10      11
//!         white  1,0,1  .7,0,1  .3,0,1  blue   0,.3,1  0,.7,1  cyan   0,1,.7  0,1,.3  green
//! count   12      13      14      15      16      17 and more
//!         .3,1,0  .7,1,0  yellow  1,.7,0  1,.3,0  red
//! ```
//!
//! - [`GridView::Lit`] (`-visualize_grid`, the course's picture): the face the ray entered by is
//!   shaded like a diffuse material of that colour under the scene's own lights and ambient
//!   light, `ambient c + sum over lights max(n.l, 0) light c` (no specular term, no shadows),
//!   so the cells read as solid blocks.
//! - [`GridView::Count`] (`-visualize_grid_count`, whitted's): the same cells in the ramp's
//!   colours unlit, so every cell's count can be read off the picture exactly.
//!
//! Rays that meet no occupied cell show the background colour; planes are never drawn.

use super::Grid;
use crate::math::{Ray, Vec3, saturate};
pub use crate::options::GridView;
use crate::scene::{Phong, Scene};
use crate::shade::phong;

/// The count ramp from 1 to 16; 17 and more are red.
const RAMP: [[f32; 3]; 16] = [
    [1.0, 1.0, 1.0],
    [1.0, 0.0, 1.0],
    [0.7, 0.0, 1.0],
    [0.3, 0.0, 1.0],
    [0.0, 0.0, 1.0],
    [0.0, 0.3, 1.0],
    [0.0, 0.7, 1.0],
    [0.0, 1.0, 1.0],
    [0.0, 1.0, 0.7],
    [0.0, 1.0, 0.3],
    [0.0, 1.0, 0.0],
    [0.3, 1.0, 0.0],
    [0.7, 1.0, 0.0],
    [1.0, 1.0, 0.0],
    [1.0, 0.7, 0.0],
    [1.0, 0.3, 0.0],
];

/// The colour of a cell holding `count` primitives (at least 1).
pub fn ramp(count: u32) -> Vec3 {
    match count {
        0 => Vec3::ZERO,
        n if n as usize <= RAMP.len() => Vec3::from_array(RAMP[n as usize - 1]),
        _ => Vec3::X,
    }
}

/// What a camera ray shows in the grid picture: the colour, and the first occupied cell's
/// entry distance and face normal (for the depth and normal images), if it met one.
pub fn pixel(
    scene: &Scene,
    grid: &Grid,
    view: GridView,
    ray: &Ray,
    tmin: f32,
) -> (Vec3, Option<(f32, Vec3)>) {
    let Some(hit) = grid.march(ray, tmin) else {
        return (scene.background, None);
    };
    let base = ramp(hit.count);
    let color = match view {
        GridView::Count => base,
        GridView::Lit => {
            let material = Phong {
                diffuse: base,
                specular: Vec3::ZERO,
                ..Phong::default()
            };
            let point = ray.at(hit.t);
            let mut color = scene.ambient * base;
            let view = ray.dir.normalize();
            for light in &scene.lights {
                let ill = light.illuminate(point);
                color += saturate(phong(
                    &material, view, hit.normal, ill.dir, ill.color, false,
                ));
            }
            saturate(color)
        }
    };
    (color, Some((hit.t, hit.normal)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_ramp_runs_from_white_through_blue_and_green_to_red() {
        assert_eq!(ramp(1), Vec3::ONE);
        assert_eq!(ramp(2), Vec3::new(1.0, 0.0, 1.0));
        assert_eq!(ramp(5), Vec3::Z);
        assert_eq!(ramp(11), Vec3::Y);
        assert_eq!(ramp(16), Vec3::new(1.0, 0.3, 0.0));
        assert_eq!(ramp(17), Vec3::X);
        assert_eq!(ramp(70), Vec3::X);
    }
}
