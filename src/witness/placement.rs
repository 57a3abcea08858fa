//! Where the witness camera stands and what it sees: the placement rule ([`WitnessSpec`],
//! [`WitnessPlace`], [`witness_camera`]: orbit the main camera about the eye ray's first hit
//! and back off until the tree is framed, or stand where the user says) and [`cutaway`], the
//! scene without the walls the witness would see from behind. The first step of the witness
//! picture, ahead of its render; it uses no other file of `witness/`.
//!
//! ```text
//! RayTree + main Camera --witness_camera--> witness Camera;  scene --cutaway--> witness scene
//! ```

use glam::Quat;

use crate::math::Vec3;
use crate::raytree::{EndKind, RayTree};
use crate::scene::{Camera, Object, Projection, Transformed};

/// Default turn of the witness camera about the vertical axis, in degrees.
pub const DEFAULT_YAW_DEG: f32 = 40.0;
/// Default extra elevation of the witness camera, in degrees.
pub const DEFAULT_PITCH_DEG: f32 = 20.0;
/// Default field of view of the witness camera, in degrees.
pub const DEFAULT_ANGLE_DEG: f32 = 60.0;
/// How far along an escaping eye ray the witness camera looks, in scene units.
pub const ESCAPE_LOOK_AT: f32 = 10.0;

/// Where the witness camera stands.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum WitnessPlace {
    /// Orbit the main camera about the look-at point by `yaw_deg` about the vertical axis and
    /// `pitch_deg` upwards, at the distance that frames the tree.
    Orbit { yaw_deg: f32, pitch_deg: f32 },
    /// Stand at `center` and look at `look_at`.
    At { center: Vec3, look_at: Vec3 },
}

/// How to place the witness camera: where, and its full field of view in degrees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WitnessSpec {
    /// Position rule.
    pub place: WitnessPlace,
    /// Full field of view, degrees.
    pub angle_deg: f32,
}

impl Default for WitnessSpec {
    fn default() -> WitnessSpec {
        WitnessSpec {
            place: WitnessPlace::Orbit {
                yaw_deg: DEFAULT_YAW_DEG,
                pitch_deg: DEFAULT_PITCH_DEG,
            },
            angle_deg: DEFAULT_ANGLE_DEG,
        }
    }
}

/// The scene's vertical axis: the signed world axis nearest the main camera's up vector.
pub fn vertical_axis(main: &Camera) -> Vec3 {
    let u = main.up;
    let a = u.abs();
    if a.y >= a.x && a.y >= a.z {
        Vec3::Y * u.y.signum()
    } else if a.x >= a.z {
        Vec3::X * u.x.signum()
    } else {
        Vec3::Z * u.z.signum()
    }
}

/// The point the default witness camera looks at: the eye ray's first hit, or a point
/// [`ESCAPE_LOOK_AT`] along it when it escapes (in front of the main camera for an empty tree).
pub fn look_at_point(main: &Camera, tree: &RayTree) -> Vec3 {
    match tree.segments.iter().find(|s| s.parent.is_none()) {
        Some(root) if root.end_kind == EndKind::Hit => root.end,
        Some(root) => root.origin + (root.end - root.origin).normalize_or_zero() * ESCAPE_LOOK_AT,
        None => main.center + main.direction * ESCAPE_LOOK_AT,
    }
}

/// The witness camera for `tree` seen by `main`, for a `width` x `height` picture.
pub fn witness_camera(
    main: &Camera,
    tree: &RayTree,
    width: u32,
    height: u32,
    spec: &WitnessSpec,
) -> Camera {
    let angle = spec.angle_deg.clamp(1.0, 170.0).to_radians();
    let vert = vertical_axis(main);
    let (center, look_at) = match spec.place {
        WitnessPlace::At { center, look_at } => (center, look_at),
        WitnessPlace::Orbit { yaw_deg, pitch_deg } => {
            let hit = look_at_point(main, tree);
            let w = orbit_direction(main, hit, vert, yaw_deg, pitch_deg);
            let (look_at, dist) = framing(main, tree, hit, w, vert, angle, width, height);
            (look_at + w * dist, look_at)
        }
    };
    let dir = (look_at - center).try_normalize().unwrap_or(main.direction);
    // Camera::new needs an up vector not parallel to the direction.
    let up = if dir.cross(vert).length() > 1e-3 {
        vert
    } else {
        main.up
    };
    let up = if dir.cross(up).length() > 1e-3 {
        up
    } else {
        dir.any_orthonormal_vector()
    };
    Camera::new(Projection::Perspective { angle }, center, dir, up)
}

/// Unit vector from the look-at point towards the witness camera: the main camera's side,
/// turned by `yaw_deg` about `vert` and raised by `pitch_deg` (elevation kept within 75
/// degrees of the horizon so the camera never looks straight down).
fn orbit_direction(main: &Camera, look_at: Vec3, vert: Vec3, yaw_deg: f32, pitch_deg: f32) -> Vec3 {
    let v = (main.center - look_at)
        .try_normalize()
        .unwrap_or(-main.direction);
    let flat = v - vert * v.dot(vert);
    let flat = flat.try_normalize().unwrap_or_else(|| {
        (-main.direction - vert * (-main.direction).dot(vert)).normalize_or(main.horizontal)
    });
    let elevation = v.dot(vert).clamp(-1.0, 1.0).asin();
    let turned = Quat::from_axis_angle(vert, yaw_deg.to_radians()) * flat;
    let limit = 75f32.to_radians();
    let e = (elevation + pitch_deg.to_radians()).clamp(-limit, limit);
    (turned * e.cos() + vert * e.sin()).normalize()
}

/// Where a witness looking along `-w` should look and from how far: the centre of the framed
/// points (seen across `w`) and the smallest distance at which they fit in the middle 85% of a
/// `width` x `height` picture with field of view `angle`. `hit` is the point the orbit turns
/// about.
#[allow(clippy::too_many_arguments)] // reason: the framing inputs, each used once
fn framing(
    main: &Camera,
    tree: &RayTree,
    hit: Vec3,
    w: Vec3,
    vert: Vec3,
    angle: f32,
    width: u32,
    height: u32,
) -> (Vec3, f32) {
    let forward = -w;
    let right = forward.cross(vert).normalize_or(main.horizontal);
    let up = right.cross(forward);
    let side = width.max(height) as f32;
    let t = (angle * 0.5).tan() * 0.85;
    let (tx, ty) = (t * width as f32 / side, t * height as f32 / side);
    // The main camera, the eye ray and every surface hit count; occluders and point lights
    // count when they lie within twice the main camera's distance of the first hit (a light
    // far away would shrink the tree to a dot; the shadow rays still point at it).
    let reach = (main.center - hit).length().max(1e-3);
    let mut points = vec![main.center];
    points.extend(tree.segments.iter().filter_map(|s| {
        let counts = s.parent.is_none()
            || s.end_kind == EndKind::Hit
            || (matches!(s.end_kind, EndKind::Occluder | EndKind::Light)
                && (s.end - hit).length() <= 2.0 * reach);
        counts.then_some(s.end)
    }));
    points.extend(
        tree.segments
            .iter()
            .filter(|s| s.parent.is_none())
            .map(|s| s.origin),
    );
    // An orthographic camera is drawn as its screen rectangle, which should fit too (the
    // witness picture has the main image's size).
    if let Projection::Orthographic { size } = main.kind {
        let (fx, fy) = (width as f32 / side * 0.5, height as f32 / side * 0.5);
        for (sx, sy) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
            points.push(
                main.center + main.horizontal * (sx * fx * size) + main.up * (sy * fy * size),
            );
        }
    }
    points.retain(|p| p.is_finite());
    // Centre the picture on the points' extent across the view direction.
    let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
    for p in &points {
        let q = *p - hit;
        let c = Vec3::new(q.dot(right), q.dot(up), 0.0);
        lo = lo.min(c);
        hi = hi.max(c);
    }
    let mid = (lo + hi) * 0.5;
    let look_at = hit + right * mid.x + up * mid.y;
    let mut dist = 0.05 * reach.max(1e-3);
    for p in &points {
        let q = *p - look_at;
        let need = q.dot(w) + (q.dot(right).abs() / tx).max(q.dot(up).abs() / ty);
        let clear = q.dot(w) + 0.05 * reach;
        dist = dist.max(need).max(clear);
    }
    (look_at, dist)
}

/// The object tree without the planes and lone triangles (walls, mirrors) that a viewer at
/// `eye` sees from behind (on the side their normal points away from), so the witness can look
/// into a room; meshes and everything else, ids included, are kept.
pub fn cutaway(obj: &Object, eye: Vec3) -> Object {
    match obj {
        Object::Plane { normal, offset, .. } if normal.dot(eye) < *offset => {
            Object::Group(Vec::new())
        }
        Object::Triangle { v, .. } if (v[1] - v[0]).cross(v[2] - v[0]).dot(eye - v[0]) < 0.0 => {
            Object::Group(Vec::new())
        }
        Object::Group(children) => {
            Object::Group(children.iter().map(|c| cutaway(c, eye)).collect())
        }
        Object::Transform(t) => {
            let local = t.inverse.transform_point3(eye);
            Object::Transform(Box::new(Transformed::new(
                t.matrix,
                cutaway(&t.child, local),
            )))
        }
        other => other.clone(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raytree::SegmentKind;
    use crate::witness::main_camera;
    use crate::witness::projection::View;

    #[test]
    fn the_default_witness_stands_to_the_right_and_above_looking_at_the_hit() {
        let main = main_camera();
        let mut tree = RayTree::new();
        let ray = crate::math::Ray::new(main.center, main.direction);
        let hit = crate::intersect::Hit {
            t: 5.0,
            normal: Vec3::Z,
            shading: Vec3::Z,
            material: 0,
            prim: 0,
        };
        tree.add_ray(SegmentKind::Eye, None, &ray, Some(hit), 0, 1.0);
        let w = witness_camera(&main, &tree, 200, 100, &WitnessSpec::default());
        let hit_point = ray.at(5.0);
        assert!(w.center.x > hit_point.x + 0.5, "to the right: {}", w.center);
        assert!(
            w.center.y > main.center.y,
            "above the main camera: {}",
            w.center
        );
        // Turned 40 degrees about the vertical axis from the main camera's side of the hit.
        let flat = |v: Vec3| Vec3::new(v.x, 0.0, v.z).normalize();
        let turn = flat(main.center - hit_point).angle_between(flat(-w.direction));
        assert!(
            (turn.to_degrees() - DEFAULT_YAW_DEG).abs() < 0.5,
            "{}",
            turn.to_degrees()
        );
        // The main camera and the hit are in the middle 85% of the picture.
        let view = View::new(&w, 200, 100, 1e-3);
        for q in [main.center, hit_point] {
            let c = view.to_camera(q);
            let p = view.to_pixel(c);
            assert!(c.z > 0.0, "{q} is behind the witness");
            assert!(
                (14.0..186.0).contains(&p[0]) && (7.0..93.0).contains(&p[1]),
                "{p:?}"
            );
        }
    }
}
