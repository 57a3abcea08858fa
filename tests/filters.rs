//! Claim: each filter's weights are symmetric (in the sign of either offset and under swapping
//! the axes) and, normalised over a pixel's support cropped at the image border, sum to 1 (a
//! film of one colour filters to that colour, at the border too); and the `-render_filter`
//! pictures match the instructor images filter7_01e (tent 1.7) and filter7_01f (Gaussian 1.7).

mod common;

use common::{course_dir, diff, read_image};
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
