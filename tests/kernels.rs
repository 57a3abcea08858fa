//! Claim: every packet kernel computes exactly what its scalar twin computes, lane by lane, for
//! every count of active lanes (1..8, at random positions), and leaves inactive lanes of the hit
//! record bit-identical (Embree's "inactive rays" test). Also the whole-geometry packet queries
//! (closest hit, any hit) against their single-ray versions.

mod common;

use common::Rng;
use whitted::Scene;
use whitted::geometry::Geometry;
use whitted::intersect::{
    intersect_plane, intersect_plane_packet, intersect_sphere, intersect_sphere_packet,
    intersect_transformed_sphere, intersect_transformed_sphere_packet, intersect_triangle,
    intersect_triangle_packet,
};
use whitted::math::{Ray, Vec3};
use whitted::packet::{HitPacket, RayPacket};
use whitted::simd::{LANES, bitmask, from_lanes, lanes, lanes_i32, mask_from_bits};

fn rand_vec(rng: &mut Rng, lo: f32, hi: f32) -> Vec3 {
    Vec3::new(rng.range(lo, hi), rng.range(lo, hi), rng.range(lo, hi))
}

/// A random mask with exactly `n` of the 8 lanes set.
fn random_mask_bits(rng: &mut Rng, n: usize) -> u32 {
    let mut lanes: Vec<u32> = (0..LANES as u32).collect();
    for i in (1..lanes.len()).rev() {
        lanes.swap(i, rng.below(i as u32 + 1) as usize);
    }
    lanes[..n].iter().fold(0, |m, l| m | 1 << l)
}

/// 8 random rays, about half aimed at `target`, with per-lane tmin (some negative, as an
/// orthographic camera's) and garbage in the lanes that will be inactive.
fn random_packet(
    rng: &mut Rng,
    target: Vec3,
    bits: u32,
) -> (RayPacket, [Ray; LANES], [f32; LANES]) {
    let rays: [Ray; LANES] = std::array::from_fn(|_| {
        let origin = rand_vec(rng, -4.0, 4.0);
        let dir = if rng.chance(0.5) {
            target + rand_vec(rng, -0.7, 0.7) - origin
        } else {
            rand_vec(rng, -1.0, 1.0)
        };
        Ray::new(origin, dir.normalize())
    });
    let tmin: [f32; LANES] = std::array::from_fn(|_| match rng.below(3) {
        0 => 0.0,
        1 => 1e-3,
        _ => -f32::MAX,
    });
    let mut packet = RayPacket::from_rays(&rays, 0.0);
    packet.tmin = from_lanes(tmin);
    packet.active = mask_from_bits(bits);
    (packet, rays, tmin)
}

/// Runs `packet_kernel` and `scalar_kernel` on the same rays for every active-lane count and
/// checks every lane.
fn check_kernel(
    name: &str,
    target: Vec3,
    packet_kernel: &dyn Fn(
        &RayPacket,
        whitted::simd::F32x8,
    ) -> (whitted::simd::Mask, whitted::simd::F32x8),
    scalar_kernel: &dyn Fn(&Ray, f32, f32) -> Option<f32>,
) {
    let mut rng = Rng::new(name.len() as u64 * 7919);
    let mut hits = 0;
    for active in 1..=LANES {
        for _ in 0..200 {
            let bits = random_mask_bits(&mut rng, active);
            let (packet, rays, tmin) = random_packet(&mut rng, target, bits);
            let tmax: [f32; LANES] = std::array::from_fn(|_| {
                if rng.chance(0.3) {
                    rng.range(0.5, 6.0)
                } else {
                    f32::INFINITY
                }
            });
            let (mask, t) = packet_kernel(&packet, from_lanes(tmax));
            let (mask, t) = (bitmask(mask), lanes(t));
            assert_eq!(
                mask & !bits,
                0,
                "{name}: a hit reported in an inactive lane"
            );
            for lane in 0..LANES {
                if bits >> lane & 1 == 0 {
                    continue;
                }
                let expected = scalar_kernel(&rays[lane], tmin[lane], tmax[lane]);
                let got = (mask >> lane & 1 == 1).then_some(t[lane]);
                assert_eq!(
                    got.map(f32::to_bits),
                    expected.map(f32::to_bits),
                    "{name}: lane {lane} of {active} active: ray {:?}",
                    rays[lane]
                );
                hits += expected.is_some() as u32;
            }
        }
    }
    assert!(
        hits > 100,
        "{name}: only {hits} hits, the test rays miss too often"
    );
}

#[test]
fn sphere_packet_equals_scalar() {
    let (c, r2) = (Vec3::new(0.3, -0.2, 0.5), 1.3);
    check_kernel(
        "sphere",
        c,
        &|p, tmax| intersect_sphere_packet(c, r2, p, tmax),
        &|r, tmin, tmax| intersect_sphere(c, r2, r, tmin, tmax),
    );
}

#[test]
fn transformed_sphere_packet_equals_scalar() {
    let inv = [0.9, 0.3, 0.0, 0.1, -0.2, 1.7, 0.4, -0.3, 0.0, 0.1, 0.6, 0.2];
    check_kernel(
        "transformed sphere",
        Vec3::new(-0.1, 0.2, -0.3),
        &|p, tmax| intersect_transformed_sphere_packet(&inv, p, tmax),
        &|r, tmin, tmax| intersect_transformed_sphere(&inv, r, tmin, tmax),
    );
}

#[test]
fn triangle_packet_equals_scalar() {
    let (v0, e1, e2) = (
        Vec3::new(-1.0, -1.0, 0.2),
        Vec3::new(2.5, 0.3, -0.4),
        Vec3::new(0.4, 2.2, 0.6),
    );
    check_kernel(
        "triangle",
        v0 + (e1 + e2) * 0.3,
        &|p, tmax| intersect_triangle_packet(v0, e1, e2, p, tmax),
        &|r, tmin, tmax| intersect_triangle(v0, e1, e2, r, tmin, tmax),
    );
}

#[test]
fn plane_packet_equals_scalar() {
    let (n, d) = (Vec3::new(0.2, 1.0, -0.3).normalize(), -0.5);
    check_kernel(
        "plane",
        n * d,
        &|p, tmax| intersect_plane_packet(n, d, p, tmax),
        &|r, tmin, tmax| intersect_plane(n, d, r, tmin, tmax),
    );
}

fn test_geometry() -> Geometry {
    let text = "PerspectiveCamera { center 0 0 10 direction 0 0 -1 up 0 1 0 angle 30 }
        Materials { numMaterials 1 Material { diffuseColor 1 1 1 } }
        Group { numObjects 6
            MaterialIndex 0
            Sphere { center 0 0 0 radius 1 }
            Transform { Translate 1 1 0 Scale 1 0.3 0.6 Sphere { center 0 0 0 radius 1 } }
            Transform { Translate -1 0 1 UniformScale 0.5 Sphere { center 0 0 0 radius 1 } }
            Triangle { vertex0 -2 -2 -1 vertex1 2 -2 -1 vertex2 0 2 -1.5 }
            Transform { Translate 0 -1 1 YRotate 30 TriangleMesh { obj_file cube.obj } }
            Plane { normal 0 1 0 offset -3 } }";
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/kernels.txt");
    let g = Geometry::from_scene(&Scene::from_str(text, &path).unwrap());
    assert!(
        !g.triangles.is_empty()
            && !g.spheres.is_empty()
            && !g.transformed.is_empty()
            && !g.planes.is_empty()
    );
    g
}

/// A lane whose hit so far is an index at an infinite distance (no bound: any hit beats it)
/// keeps that index where it hits nothing, also where it passes between the spheres of a leaf
/// it enters: the packet leaf takes the nearest among the spheres each lane hits, so a miss is
/// never a tie at infinity with a smaller index. Plain and transformed spheres, every count of
/// active lanes from 3 (fewer go ray by ray).
#[test]
fn a_miss_keeps_an_index_at_infinity() {
    for transformed in [false, true] {
        // 8 spheres in a row along x, 2 apart, radius 0.5: gaps between them inside the leaves
        let spheres: String = (0..8)
            .map(|k| {
                let x = 2.0 * k as f32;
                if transformed {
                    format!("Transform {{ Translate {x} 0 0 Scale 0.5 0.5 0.4 Sphere {{ center 0 0 0 radius 1 }} }} ")
                } else {
                    format!("Sphere {{ center {x} 0 0 radius 0.5 }} ")
                }
            })
            .collect();
        let text = format!(
            "PerspectiveCamera {{ center 0 0 10 direction 0 0 -1 up 0 1 0 angle 30 }}
            Materials {{ numMaterials 1 Material {{ diffuseColor 1 1 1 }} }}
            Group {{ numObjects 8 MaterialIndex 0 {spheres} }}"
        );
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/row.txt");
        let g = Geometry::from_scene(&Scene::from_str(&text, &path).unwrap());
        // lane 0 hits the first sphere, the others go down z through the gaps
        let rays: [Ray; LANES] = std::array::from_fn(|l| {
            let x = if l == 0 { 0.0 } else { 2.0 * l as f32 - 1.0 };
            Ray::new(Vec3::new(x, 0.1, 5.0), Vec3::new(0.0, 0.0, -1.0))
        });
        for active in 3..=LANES {
            let mut packet = RayPacket::from_rays(&rays, 0.0);
            packet.active = mask_from_bits((1u32 << active) - 1);
            const KEPT: i32 = 1000;
            let mut hit = HitPacket {
                t: from_lanes([f32::INFINITY; LANES]),
                prim: whitted::simd::I32x8::new([KEPT; LANES]),
            };
            g.closest_hit_packet(&packet, &mut hit);
            let (t, prim) = (lanes(hit.t), lanes_i32(hit.prim));
            let first = g
                .closest_hit(&rays[0], 0.0, f32::INFINITY)
                .expect("lane 0 hits");
            assert_eq!(
                (t[0], prim[0]),
                (first.0, first.1 as i32),
                "transformed {transformed}"
            );
            for l in 1..active {
                assert_eq!(g.closest_hit(&rays[l], 0.0, f32::INFINITY), None);
                assert_eq!(
                    (t[l], prim[l]),
                    (f32::INFINITY, KEPT),
                    "transformed {transformed}, lane {l}"
                );
            }
        }
    }
}

#[test]
fn geometry_closest_hit_packet_equals_single_rays_and_keeps_inactive_lanes() {
    let g = test_geometry();
    let mut rng = Rng::new(11);
    for active in 1..=LANES {
        for _ in 0..100 {
            let bits = random_mask_bits(&mut rng, active);
            let (packet, rays, tmin) = random_packet(&mut rng, Vec3::ZERO, bits);
            // Inactive lanes start with garbage that must survive untouched.
            let before = HitPacket {
                t: from_lanes(std::array::from_fn(|i| {
                    if bits >> i & 1 == 1 {
                        f32::INFINITY
                    } else {
                        1234.5 + i as f32
                    }
                })),
                prim: whitted::simd::I32x8::new(std::array::from_fn(|i| {
                    if bits >> i & 1 == 1 {
                        -1
                    } else {
                        77 + i as i32
                    }
                })),
            };
            let mut hit = before;
            g.closest_hit_packet(&packet, &mut hit);
            let (t, prim) = (lanes(hit.t), lanes_i32(hit.prim));
            let (t0, prim0) = (lanes(before.t), lanes_i32(before.prim));
            for lane in 0..LANES {
                if bits >> lane & 1 == 0 {
                    assert_eq!(
                        t[lane].to_bits(),
                        t0[lane].to_bits(),
                        "inactive lane {lane} t changed"
                    );
                    assert_eq!(prim[lane], prim0[lane], "inactive lane {lane} prim changed");
                    continue;
                }
                let expected = g.closest_hit(&rays[lane], tmin[lane], f32::INFINITY);
                let got = (prim[lane] >= 0).then(|| (t[lane], prim[lane] as u32));
                assert_eq!(got, expected, "lane {lane}: {:?}", rays[lane]);
            }
        }
    }
}

#[test]
fn geometry_occluded_packet_equals_single_rays() {
    let g = test_geometry();
    let mut rng = Rng::new(12);
    for active in 1..=LANES {
        for _ in 0..100 {
            let bits = random_mask_bits(&mut rng, active);
            let (packet, rays, tmin) = random_packet(&mut rng, Vec3::ZERO, bits);
            let tmax: [f32; LANES] = std::array::from_fn(|_| rng.range(0.1, 8.0));
            let occluded = bitmask(g.occluded_packet(&packet, from_lanes(tmax)));
            assert_eq!(
                occluded & !bits,
                0,
                "occlusion reported in an inactive lane"
            );
            for lane in 0..LANES {
                if bits >> lane & 1 == 1 {
                    let expected = g.occluded(&rays[lane], tmin[lane], tmax[lane]);
                    assert_eq!(
                        occluded >> lane & 1 == 1,
                        expected,
                        "lane {lane}: {:?}",
                        rays[lane]
                    );
                }
            }
        }
    }
}
