//! Claim: each filter's weights are symmetric (in the sign of either offset and under swapping
//! the axes) and, normalised over a pixel's support cropped at the image border, sum to 1 (a
//! film of one colour filters to that colour, at the border too); and the `-render_filter`
//! pictures match the instructor images filter7_01e (tent 1.7) and filter7_01f (Gaussian 1.7);
//! and a pixel of one sample under a filter no wider than the pixel is, bit for bit, the
//! weighted average of its one sample (its colour, or black where the weight is zero).

mod common;

use common::{Rng, course_dir, diff, read_image};
use whitted::film::{SampleRows, filter_rows};
use whitted::filter::{Filter, Shape};
use whitted::math::{Vec2, Vec3};
use whitted::sample_images::render_filter;
use whitted::sampler::{Pattern, Sampler};

fn filters() -> Vec<Filter> {
    let mut all = Vec::new();
    for shape in [Shape::Box, Shape::Tent, Shape::Gaussian] {
        for size in [0.3, 0.5, 0.6, 1.0, 1.5, 1.7, 2.3, 3.1] {
            all.push(Filter { shape, size });
        }
    }
    all
}

#[test]
fn weights_are_symmetric() {
    for f in filters() {
        for a in 0..40 {
            for b in 0..40 {
                let (x, y) = (a as f32 * 0.137 - 2.6, b as f32 * 0.091 - 1.8);
                let w = f.weight(x, y);
                assert!((0.0..=1.0).contains(&w), "{f:?} ({x}, {y}): {w}");
                assert_eq!(w, f.weight(-x, y), "{f:?} ({x}, {y})");
                assert_eq!(w, f.weight(x, -y), "{f:?} ({x}, {y})");
                assert_eq!(w, f.weight(y, x), "{f:?} ({x}, {y})");
            }
        }
        assert_eq!(f.weight(0.0, 0.0), 1.0, "{f:?}");
    }
}

#[test]
fn the_filter_picture_is_symmetric() {
    for f in filters() {
        let img = render_filter(9, 9, 20, &f);
        let px = |x: usize, y: usize| &img.data[(y * 181 + x) * 3..(y * 181 + x) * 3 + 3];
        for y in 0..181 {
            for x in 0..181 {
                assert_eq!(px(x, y), px(180 - x, y), "{f:?} ({x}, {y})");
                assert_eq!(px(x, y), px(x, 180 - y), "{f:?} ({x}, {y})");
                assert_eq!(px(x, y), px(y, x), "{f:?} ({x}, {y})");
            }
        }
    }
}

#[test]
fn normalised_weights_sum_to_one_at_the_border_too() {
    let (w, h) = (7u32, 5u32);
    for f in filters().into_iter().filter(|f| f.size >= 0.5) {
        for (pattern, count) in [
            (Pattern::Uniform, 1),
            (Pattern::Uniform, 9),
            (Pattern::Jittered, 4),
            (Pattern::Random, 6),
        ] {
            let s = Sampler {
                pattern,
                count,
                seed: 3,
            };
            let n = count as usize;
            let offsets: Vec<Vec2> = (0..h)
                .flat_map(|y| (0..w).flat_map(move |x| (0..count).map(move |k| (x, y, k))))
                .map(|(x, y, k)| s.offset(x, y, k))
                .collect();
            for c in [
                Vec3::new(0.4, 0.2, 0.8),
                Vec3::splat(1.0),
                Vec3::new(0.3, 0.7, 0.1),
            ] {
                let colors = vec![c; offsets.len()];
                let row = w as usize * n;
                let rows = SampleRows {
                    y0: 0,
                    x0: 0,
                    spp: count,
                    rows: (0..h as usize)
                        .map(|y| {
                            (
                                &colors[y * row..(y + 1) * row],
                                &offsets[y * row..(y + 1) * row],
                            )
                        })
                        .collect(),
                };
                let mut out = vec![Vec3::ZERO; (w * h) as usize];
                filter_rows(&f, &rows, 0..w, 0..h, w, h, &mut out);
                for (k, got) in out.iter().enumerate() {
                    assert!(
                        (*got - c).abs().max_element() <= 1e-6,
                        "{f:?} {s:?} pixel {k}: {got} for {c}"
                    );
                }
            }
        }
    }
}

#[test]
fn the_filter_pictures_match_the_instructor_images() {
    let Some(course) = course_dir() else {
        eprintln!("skipped: WHITTED_COURSE_DIR is not set");
        return;
    };
    let refs = course.join("reference_images/assignment7");
    for (name, shape) in [
        ("filter7_01e", Shape::Tent),
        ("filter7_01f", Shape::Gaussian),
    ] {
        let ours = render_filter(9, 9, 20, &Filter { shape, size: 1.7 });
        let theirs = read_image(&refs.join(format!("{name}.png")));
        let d = diff(&ours, &theirs, 0);
        eprintln!("{name}: {} of {} pixels differ at all", d.over, d.pixels);
        assert_eq!(d.over, 0, "{name}: max difference {}", d.max);
    }
}

/// The weighted average of a pixel's one sample as the sums make it, restated: `w * c / w` in
/// `f64`, black when the weight is not positive.
fn average_of_one(f: &Filter, c: Vec3, o: Vec2) -> Vec3 {
    let w = f.weight(o.x - 0.5, o.y - 0.5) as f64;
    if w > 0.0 {
        Vec3::new(
            ((w * c.x as f64) / w) as f32,
            ((w * c.y as f64) / w) as f32,
            ((w * c.z as f64) / w) as f32,
        )
    } else {
        Vec3::ZERO
    }
}

#[test]
fn one_sample_per_pixel_filters_to_the_weighted_average_of_it_bit_for_bit() {
    let (w, h) = (13u32, 4u32);
    let narrow: Vec<Filter> = filters()
        .into_iter()
        .chain([0.1, 0.2, 0.25].map(|size| Filter {
            shape: Shape::Gaussian,
            size,
        }))
        .filter(|f| f.support_radius() == 0)
        .collect();
    assert!(
        narrow.len() >= 6,
        "box, tent and Gaussian filters of radius 0"
    );
    let mut rng = Rng::new(7);
    let mut zero = 0;
    for f in &narrow {
        let n = (w * h) as usize;
        // colours of every magnitude, with signed zeros and subnormals among them
        let special = [0.0, -0.0, 1e-42, 3.0e38, 1.0, 0.1, -2.5];
        let colors: Vec<Vec3> = (0..n)
            .map(|_| {
                let mut v = || match rng.below(3) {
                    0 => special[rng.below(special.len() as u32) as usize],
                    1 => rng.range(-1.0, 4.0),
                    _ => f32::from_bits(rng.next_u32() & 0x7f7f_ffff),
                };
                Vec3::new(v(), v(), v())
            })
            .collect();
        let offsets: Vec<Vec2> = (0..n).map(|_| Vec2::new(rng.f32(), rng.f32())).collect();
        let rows = SampleRows {
            y0: 0,
            x0: 0,
            spp: 1,
            rows: (0..h as usize)
                .map(|y| {
                    let row = y * w as usize..(y + 1) * w as usize;
                    (&colors[row.clone()], &offsets[row])
                })
                .collect(),
        };
        // the whole image, and a window of it (columns 3..11 of rows 1..4)
        for (cols, rs) in [(0..w, 0..h), (3..11, 1..4)] {
            let mut out = vec![Vec3::splat(9.0); cols.len() * rs.len()];
            filter_rows(f, &rows, cols.clone(), rs.clone(), w, h, &mut out);
            for (k, got) in out.iter().enumerate() {
                let (x, y) = (
                    cols.start + (k % cols.len()) as u32,
                    rs.start + (k / cols.len()) as u32,
                );
                let i = (y * w + x) as usize;
                let want = average_of_one(f, colors[i], offsets[i]);
                zero += (f.weight(offsets[i].x - 0.5, offsets[i].y - 0.5) <= 0.0) as u32;
                assert_eq!(
                    got.to_array().map(f32::to_bits),
                    want.to_array().map(f32::to_bits),
                    "{f:?} pixel ({x}, {y}): colour {:?} at offset {:?}",
                    colors[i],
                    offsets[i]
                );
            }
        }
    }
    assert!(zero > 0, "some samples fall outside their narrow filter");
}
