//! Claim: the 8-wide BVH and its leaf blocks hold their invariants (`validate_bvh`) for every
//! builder setting and on the edge cases (one primitive, every primitive at one point, flat
//! scenes, more primitives than a leaf may hold at one point), leaf blocks with partly filled
//! lanes report only their own primitives, and every path through the tree (single rays, 8-ray
//! packets, streams of packets, lists of rays going down together, the per-group choice over
//! batches of many groups) gives the same `(t, primitive)` bit for
//! bit on the same rays, ties in `t` included, and leaves a lane's hit as it was where nothing
//! in the tree beats it.

mod common;

use common::Rng;
use whitted::bvh::MAX_STREAM;
use whitted::bvh::build::BuildSettings;
use whitted::geometry::{Geometry, LIST_PACKETS, Path, SMALL_TREE_NODES};
use whitted::math::{Ray, Vec3};
use whitted::packet::{HitPacket, RayPacket};
use whitted::simd::{
    F32x8, I32x8, LANES, Mask, bitmask, from_lanes, lanes, lanes_i32, mask_from_bits,
};

fn v(rng: &mut Rng, lo: f32, hi: f32) -> Vec3 {
    Vec3::new(rng.range(lo, hi), rng.range(lo, hi), rng.range(lo, hi))
}

fn push_triangle(g: &mut Geometry, t: [Vec3; 3]) {
    let n = (t[1] - t[0]).cross(t[2] - t[0]).normalize();
    let id = g.triangles.len() as u32;
    g.triangles.push(t, n, 0, id);
}

/// Triangles and spheres scattered in a box, some sharing an edge (ties in `t` along it).
fn soup(rng: &mut Rng, n: usize) -> Geometry {
    let mut g = Geometry::default();
    for _ in 0..n {
        let c = v(rng, -4.0, 4.0);
        if rng.chance(0.7) {
            let (a, b) = (c + v(rng, -0.6, 0.6), c + v(rng, -0.6, 0.6));
            push_triangle(&mut g, [c, a, b]);
            if rng.chance(0.3) {
                push_triangle(&mut g, [a, c, c + v(rng, -0.6, 0.6)]);
            }
        } else {
            let id = 1_000_000 + g.spheres.len() as u32;
            g.spheres.push(c, rng.range(0.05, 0.5), 0, id);
        }
    }
    g
}

fn settings() -> Vec<BuildSettings> {
    let d = BuildSettings::default();
    let mut all = vec![d];
    for (min_leaf, max_leaf) in [(1, 1), (1, 4), (2, 8), (4, 16), (8, 8)] {
        all.push(BuildSettings {
            min_leaf,
            max_leaf,
            ..d
        });
    }
    for max_bins in [2, 5, 16, 32] {
        all.push(BuildSettings { max_bins, ..d });
    }
    for traversal_cost in [0.0, 0.25, 4.0] {
        all.push(BuildSettings {
            traversal_cost,
            ..d
        });
    }
    all
}

fn built(g: &Geometry, s: &BuildSettings) -> Geometry {
    let mut b = g.clone();
    b.build_bvh_with(s);
    b.validate_bvh().unwrap_or_else(|e| panic!("{s:?}: {e}"));
    b
}

#[test]
fn every_builder_setting_validates() {
    let mut rng = Rng::new(1);
    let scenes = [
        soup(&mut rng, 1),
        soup(&mut rng, 9),
        soup(&mut rng, 700),
        soup(&mut rng, 5000),
    ];
    for g in &scenes {
        for s in settings() {
            let b = built(g, &s);
            assert!(!b.bvh().is_empty());
        }
    }
}

#[test]
fn edge_cases_validate() {
    let d = BuildSettings::default();
    // One primitive of each kind: a leaf at the root.
    let mut one = Geometry::default();
    push_triangle(&mut one, [Vec3::ZERO, Vec3::X, Vec3::Y]);
    let b = built(&one, &d);
    assert!(b.bvh().root().is_leaf() && b.bvh().nodes().is_empty());
    let mut one = Geometry::default();
    one.spheres.push(Vec3::ONE, 0.5, 0, 0);
    built(&one, &d);
    // Every primitive at one point: no spatial split exists; leaves by halves, in index order.
    let mut point = Geometry::default();
    for _ in 0..1000 {
        push_triangle(&mut point, [Vec3::splat(2.0); 3]);
    }
    for id in 0..300 {
        point.spheres.push(Vec3::splat(2.0), 0.0, 0, id);
    }
    for s in settings() {
        built(&point, &s);
    }
    // Flat scenes: every triangle in the plane y = 1, and a row along x (two flat axes).
    let mut rng = Rng::new(3);
    let mut flat = Geometry::default();
    let mut row = Geometry::default();
    for _ in 0..2000 {
        let (x, z) = (rng.range(-5.0, 5.0), rng.range(-5.0, 5.0));
        let p = Vec3::new(x, 1.0, z);
        push_triangle(&mut flat, [p, p + Vec3::X * 0.1, p + Vec3::Z * 0.1]);
        let q = Vec3::new(x, 0.0, 0.0);
        push_triangle(&mut row, [q, q + Vec3::X * 0.01, q]);
    }
    for s in settings() {
        built(&flat, &s);
        built(&row, &s);
    }
    // No primitive at all.
    let b = built(&Geometry::default(), &d);
    assert!(b.bvh().is_empty());
}

#[test]
fn partly_filled_blocks_hit_only_their_primitives() {
    // n triangles in one leaf: blocks of 4 with 4 - n % 4 unused lanes, which hold degenerate
    // triangles at the origin (and spheres of negative radius squared): a ray through the
    // origin must hit nothing but the real primitives, on every path.
    for n in 1..=9 {
        let mut g = Geometry::default();
        for k in 0..n {
            let z = 1.0 + k as f32;
            push_triangle(
                &mut g,
                [
                    Vec3::new(-1.0, -1.0, z),
                    Vec3::new(1.0, -1.0, z),
                    Vec3::new(0.0, 1.0, z),
                ],
            );
        }
        for k in 0..n {
            g.spheres
                .push(Vec3::new(5.0, 0.0, k as f32), 0.25, 0, 100 + k as u32);
        }
        let s = BuildSettings {
            min_leaf: 16,
            max_leaf: 16,
            ..BuildSettings::default()
        };
        let b = built(&g, &s);
        let blocks = b.blocks();
        let partly = |prims: Vec<[u32; 4]>| prims.iter().any(|p| p.contains(&u32::MAX));
        let tri: Vec<[u32; 4]> = blocks.triangles.iter().map(|t| t.prim).collect();
        let sph: Vec<[u32; 4]> = blocks.spheres.iter().map(|s| s.prim).collect();
        assert_eq!(partly(tri), n % 4 != 0, "{n} triangles");
        assert_eq!(partly(sph), n % 4 != 0, "{n} spheres");
        // Through the origin, where the unused triangle lanes sit, away from the triangles.
        let origin_ray = Ray::new(Vec3::new(0.0, 0.0, -3.0), Vec3::new(0.0, 0.0, -1.0));
        let miss = Ray::new(
            Vec3::new(3.0, 3.0, 3.0),
            (Vec3::ZERO - Vec3::splat(3.0)).normalize(),
        );
        let up = Ray::new(Vec3::new(0.0, 0.0, 1.5), Vec3::Z);
        let sphere_row = Ray::new(Vec3::new(5.0, 0.0, -2.0), Vec3::Z);
        for ray in [origin_ray, miss, up, sphere_row] {
            let expected = g.closest_hit(&ray, 0.0, f32::INFINITY);
            assert_eq!(
                b.closest_hit(&ray, 0.0, f32::INFINITY),
                expected,
                "{n}: {ray:?}"
            );
            for path in Path::ALL {
                let rays = [RayPacket::from_rays(&[ray], 0.0)];
                let mut hit = [HitPacket::new(f32::INFINITY)];
                b.closest_hit_path(path, &rays, &mut hit);
                let got = hit[0].lane(0).map(|(t, p)| (t, p as u32));
                assert_eq!(got, expected, "{n} {path:?}: {ray:?}");
                let mut occ = [Mask::default()];
                b.occluded_path(path, &rays, &[F32x8::splat(f32::INFINITY)], &mut occ);
                assert_eq!(bitmask(occ[0]) & 1 == 1, expected.is_some(), "{n} {path:?}");
            }
        }
        // the up ray starts between the first two triangles: it hits the second (index 1)
        if n >= 2 {
            assert_eq!(b.closest_hit(&up, 0.0, f32::INFINITY).map(|h| h.1), Some(1));
        }
    }
}

/// Random rays: some from far away towards the soup, some from inside it, some axis-parallel;
/// groups of `MAX_STREAM` packets, some coherent (one origin, nearby directions).
fn ray_groups(rng: &mut Rng, groups: usize) -> Vec<Vec<RayPacket>> {
    (0..groups)
        .map(|g| {
            let coherent = g % 2 == 0;
            let eye = v(rng, -9.0, 9.0);
            let aim = v(rng, -2.0, 2.0);
            (0..MAX_STREAM)
                .map(|_| {
                    let rays: [Ray; LANES] = std::array::from_fn(|_| {
                        let (o, d) = if coherent {
                            (eye, aim + v(rng, -0.3, 0.3) - eye)
                        } else {
                            let o = v(rng, -6.0, 6.0);
                            (o, v(rng, -1.0, 1.0))
                        };
                        let mut d = d.normalize_or(Vec3::X);
                        if rng.chance(0.05) {
                            d = [Vec3::X, -Vec3::Y, Vec3::Z][rng.below(3) as usize];
                        }
                        Ray::new(o, d)
                    });
                    let mut p = RayPacket::from_rays(&rays, 1e-3);
                    p.active = mask_from_bits(rng.below(255) + 1);
                    // every fourth group has lanes starting behind their origin, as an
                    // orthographic camera's do (walks that are not forward)
                    if g % 4 == 3 {
                        p.tmin = from_lanes(std::array::from_fn(|_| {
                            if rng.chance(0.5) { -0.5 } else { 1e-3 }
                        }));
                    }
                    p
                })
                .collect()
        })
        .collect()
}

#[test]
fn single_rays_packets_and_streams_agree_bit_for_bit() {
    let mut rng = Rng::new(7);
    for n in [40, 3000] {
        let g = built(&soup(&mut rng, n), &BuildSettings::default());
        for group in ray_groups(&mut rng, 60) {
            let tmax: Vec<F32x8> = group
                .iter()
                .map(|_| from_lanes(std::array::from_fn(|_| rng.range(0.5, 20.0))))
                .collect();
            // reference: one ray at a time through the single-ray walk
            let single: Vec<Vec<Option<(u32, i32)>>> = group
                .iter()
                .map(|p| {
                    let (tmin, bits) = (lanes(p.tmin), bitmask(p.active));
                    (0..LANES)
                        .map(|l| {
                            (bits >> l & 1 == 1)
                                .then(|| g.closest_hit(&p.ray(l), tmin[l], f32::INFINITY))
                                .flatten()
                                .map(|(t, prim)| (t.to_bits(), prim as i32))
                        })
                        .collect()
                })
                .collect();
            let occluded: Vec<u32> = group
                .iter()
                .zip(&tmax)
                .map(|(p, t)| {
                    let (tmin, tmax, bits) = (lanes(p.tmin), lanes(*t), bitmask(p.active));
                    (0..LANES)
                        .filter(|&l| bits >> l & 1 == 1 && g.occluded(&p.ray(l), tmin[l], tmax[l]))
                        .fold(0, |m, l| m | 1 << l)
                })
                .collect();
            for path in Path::ALL {
                let mut hits = vec![HitPacket::new(f32::INFINITY); group.len()];
                g.closest_hit_path(path, &group, &mut hits);
                for (k, (h, p)) in hits.iter().zip(&group).enumerate() {
                    let (t, prim, bits) = (lanes(h.t), lanes_i32(h.prim), bitmask(p.active));
                    for l in 0..LANES {
                        let got = (prim[l] >= 0).then(|| (t[l].to_bits(), prim[l]));
                        if bits >> l & 1 == 0 {
                            assert_eq!((t[l], prim[l]), (f32::INFINITY, -1), "inactive lane");
                        } else {
                            assert_eq!(
                                got, single[k][l],
                                "{n} prims, {path:?}, packet {k} lane {l}"
                            );
                        }
                    }
                }
                let mut occ = vec![Mask::default(); group.len()];
                g.occluded_path(path, &group, &tmax, &mut occ);
                let bits: Vec<u32> = occ.iter().map(|m| bitmask(*m)).collect();
                assert_eq!(bits, occluded, "{n} prims, {path:?}: occlusion");
            }
            // the batch (the wavefront's and the bench's entry) agrees too
            let mut hits = vec![HitPacket::new(f32::INFINITY); group.len()];
            g.closest_hit_batch(&group, &mut hits);
            for (k, h) in hits.iter().enumerate() {
                let (t, prim) = (lanes(h.t), lanes_i32(h.prim));
                for l in 0..LANES {
                    let got = (prim[l] >= 0).then(|| (t[l].to_bits(), prim[l]));
                    assert!(got == single[k][l] || single[k][l].is_none() && got.is_none());
                }
            }
        }
    }
}

#[test]
fn ties_go_to_the_smaller_index_on_every_path() {
    // 50 copies of one triangle and 50 of one sphere: every ray that hits hits them all at
    // the same t; the answer must be the first copy whatever order the walk met them in.
    let mut g = Geometry::default();
    for _ in 0..50 {
        push_triangle(
            &mut g,
            [
                Vec3::new(-1.0, -1.0, 0.0),
                Vec3::new(1.0, -1.0, 0.0),
                Vec3::Y,
            ],
        );
    }
    for id in 0..50 {
        g.spheres.push(Vec3::new(4.0, 0.0, 0.0), 1.0, 0, id);
    }
    let b = built(&g, &BuildSettings::default());
    let mut rng = Rng::new(9);
    for _ in 0..100 {
        let target = if rng.chance(0.5) {
            Vec3::ZERO
        } else {
            Vec3::new(4.0, 0.0, 0.0)
        };
        let o = Vec3::new(rng.range(-3.0, 7.0), rng.range(-2.0, 2.0), -6.0);
        let rays: [Ray; LANES] =
            std::array::from_fn(|_| Ray::new(o, (target + v(&mut rng, -0.3, 0.3) - o).normalize()));
        let first = if target == Vec3::ZERO { 0 } else { 50 };
        let group = vec![RayPacket::from_rays(&rays, 0.0); 2];
        for path in Path::ALL {
            let mut hits = vec![HitPacket::new(f32::INFINITY); 2];
            b.closest_hit_path(path, &group, &mut hits);
            for (l, ray) in rays.iter().enumerate() {
                let single = b.closest_hit(ray, 0.0, f32::INFINITY);
                assert_eq!(single, g.closest_hit(ray, 0.0, f32::INFINITY));
                if let Some((_, p)) = single {
                    assert_eq!(p, first, "{path:?}");
                }
                let got = hits[0].lane(l).map(|(t, p)| (t, p as u32));
                assert_eq!(got, single, "{path:?} lane {l}");
            }
        }
    }
}

/// A lane whose current hit is nearer than anything the tree holds for it (or that misses the
/// tree) keeps that hit on every path: the single-ray batch starts no walk for a lane its
/// packet's root test sends nowhere, and no path may overwrite a hit it did not beat.
#[test]
fn lanes_with_a_nearer_hit_keep_it_on_every_path() {
    let mut rng = Rng::new(11);
    let g = built(&soup(&mut rng, 3000), &BuildSettings::default());
    const KEPT: i32 = 7_000_000;
    for group in ray_groups(&mut rng, 40) {
        // lanes start with a hit of their own: far, near (0.25, where the soup seldom is), at
        // infinity (an index with no bound: any hit beats it, a miss keeps it) or none
        let start: Vec<([f32; LANES], [i32; LANES])> = group
            .iter()
            .map(|_| {
                let mut t = [f32::INFINITY; LANES];
                let mut prim = [-1; LANES];
                for l in 0..LANES {
                    match rng.below(4) {
                        0 => (t[l], prim[l]) = (0.25, KEPT),
                        1 => (t[l], prim[l]) = (rng.range(1.0, 30.0), KEPT + 1),
                        2 => prim[l] = KEPT + 2,
                        _ => {}
                    }
                }
                (t, prim)
            })
            .collect();
        for path in Path::ALL {
            let mut hits: Vec<HitPacket> = start
                .iter()
                .map(|(t, prim)| HitPacket {
                    t: from_lanes(*t),
                    prim: I32x8::new(*prim),
                })
                .collect();
            g.closest_hit_path(path, &group, &mut hits);
            for (k, (h, p)) in hits.iter().zip(&group).enumerate() {
                let (t, prim) = (lanes(h.t), lanes_i32(h.prim));
                let (tmin, bits) = (lanes(p.tmin), bitmask(p.active));
                let (t0, p0) = start[k];
                for l in 0..LANES {
                    let want = if bits >> l & 1 == 0 {
                        (t0[l], p0[l])
                    } else {
                        match g.closest_hit(&p.ray(l), tmin[l], t0[l]) {
                            Some((t, prim)) => (t, prim as i32),
                            None => (t0[l], p0[l]),
                        }
                    };
                    assert_eq!(
                        (t[l].to_bits(), prim[l]),
                        (want.0.to_bits(), want.1),
                        "{path:?}, packet {k} lane {l}"
                    );
                }
            }
        }
    }
}

/// A batch of many groups in a tree big enough for the lists ([`SMALL_TREE_NODES`] interior
/// nodes or more), more packets than [`LIST_PACKETS`]: the incoherent groups go down the tree
/// as lists, a first run of them when [`LIST_PACKETS`] wait and the rest at the end, among
/// streams, lanes behind their origin and inactive lanes; every lane gets the single-ray walk's
/// `(t, primitive)` bit for bit (or keeps its own hit where nothing beats it), and inactive
/// lanes are untouched.
#[test]
fn a_batch_of_many_groups_takes_the_lists_and_agrees_with_single_rays() {
    let mut rng = Rng::new(13);
    let s = BuildSettings {
        min_leaf: 1,
        max_leaf: 4,
        ..BuildSettings::default()
    };
    let g = built(&soup(&mut rng, 12_000), &s);
    assert!(
        g.bvh().nodes().len() >= SMALL_TREE_NODES,
        "a tree too small for the lists"
    );
    let groups = ray_groups(&mut rng, LIST_PACKETS / MAX_STREAM + 90);
    let listed = groups
        .iter()
        .filter(|r| g.choose_path(r) == Path::Lists)
        .count();
    assert!(
        listed * MAX_STREAM > LIST_PACKETS,
        "{listed} groups on the lists"
    );
    let rays: Vec<RayPacket> = groups.concat();
    const KEPT: i32 = 7_000_000;
    let start: Vec<HitPacket> = rays
        .iter()
        .map(|_| {
            let t: [f32; LANES] = std::array::from_fn(|_| match rng.below(3) {
                0 => 0.25,
                1 => rng.range(1.0, 30.0),
                _ => f32::INFINITY,
            });
            let prim = t.map(|t| if t.is_finite() { KEPT } else { -1 });
            HitPacket {
                t: from_lanes(t),
                prim: I32x8::new(prim),
            }
        })
        .collect();
    let mut hits = start.clone();
    g.closest_hit_batch(&rays, &mut hits);
    for (k, ((h, p), h0)) in hits.iter().zip(&rays).zip(&start).enumerate() {
        let (t, prim) = (lanes(h.t), lanes_i32(h.prim));
        let (t0, p0) = (lanes(h0.t), lanes_i32(h0.prim));
        let (tmin, bits) = (lanes(p.tmin), bitmask(p.active));
        for l in 0..LANES {
            let want = match g.closest_hit(&p.ray(l), tmin[l], t0[l]) {
                Some((t, prim)) if bits >> l & 1 == 1 => (t, prim as i32),
                _ => (t0[l], p0[l]),
            };
            assert_eq!(
                (t[l].to_bits(), prim[l]),
                (want.0.to_bits(), want.1),
                "packet {k} lane {l}"
            );
        }
    }
}
