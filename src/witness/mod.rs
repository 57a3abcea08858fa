//! The picture of a ray tree: the scene seen by a second, "witness" camera placed beside the
//! main one, with the tree's segments drawn over it in the course's colours (eye gray, shadow
//! green, reflected red, transmitted blue; blocked shadow rays dashed dark green), the main
//! camera drawn as a small white frustum, lights as yellow dots and a legend.
//!
//! ```text
//! RayTree + main Camera --witness_camera--> Camera --render--> Frame --draw_ray_tree--> Rgb8
//! ```
//!
//! The witness camera ([`witness_camera`], default [`WitnessPlace::Orbit`]): it sees the eye
//! ray's first hit (or, if the eye ray escapes, the point [`ESCAPE_LOOK_AT`] along it) from the
//! main camera's side of the scene turned [`DEFAULT_YAW_DEG`] degrees about the scene's vertical
//! axis (the world axis nearest the main camera's up vector; positive turns to the main
//! camera's right) and raised [`DEFAULT_PITCH_DEG`] degrees, with a [`DEFAULT_ANGLE_DEG`] degree
//! field of view. It frames the main camera, the eye ray, and the tree's hits, occluders and
//! point lights within twice the main camera's distance of that hit (farther ones may leave
//! the picture): centred on their extent across the view, as near as keeps them in the middle
//! 85% of the picture. [`WitnessPlace::At`] places it explicitly instead. The witness sees the
//! scene through [`cutaway`]: planes and lone triangles it would see from behind are left out,
//! so it can look into a room of walls (the facing mirrors) from outside.
//!
//! Drawing: segments are clipped against the witness camera's near plane in 3D and against the
//! image in 2D, drawn 2-3 pixels wide (scaled with the image) with anti-aliased edges over a dark
//! halo, so they read on any background; parts hidden behind a surface (by the witness frame's
//! depth) are drawn fainter.
//!
//! One job per file, lowest first; each uses only the files above it in this list, and this
//! file only names them and re-exports their public items:
//!
//! ```text
//! font.rs        5x7 bitmap glyphs                                  (uses nothing here)
//! placement.rs   WitnessSpec -> witness Camera; cutaway of the scene (uses nothing here)
//! projection.rs  View: world point -> pixel + depth, near clipping   (placement's default angle)
//! canvas.rs      Canvas + Pen: lines, halos, dots, panels, text      (projection, font)
//! overlay.rs     draw_ray_tree: camera, segments, ends, legend       (all of the above)
//! ```

// The heatmap's legend (`crate::heatmap`) draws with the same canvas and font.
pub(crate) mod canvas;
mod font;
mod overlay;
mod placement;
mod projection;

pub use self::overlay::{draw_ray_tree, kind_color};
pub use self::placement::{
    DEFAULT_ANGLE_DEG, DEFAULT_PITCH_DEG, DEFAULT_YAW_DEG, ESCAPE_LOOK_AT, WitnessPlace,
    WitnessSpec, cutaway, look_at_point, vertical_axis, witness_camera,
};

/// The main camera the unit tests of `witness/` look through.
#[cfg(test)]
fn main_camera() -> crate::scene::Camera {
    crate::scene::Camera::new(
        crate::scene::Projection::Perspective { angle: 0.6 },
        crate::math::Vec3::new(0.0, 1.0, 6.0),
        crate::math::Vec3::new(0.0, -0.2, -1.0),
        crate::math::Vec3::Y,
    )
}
