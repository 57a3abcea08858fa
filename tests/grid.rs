//! Claim: the grid marks the cells the handouts say, checked by hand: a sphere under no transform
//! marks the cells whose centre is within its radius, a sphere under a `Transform` (even an
//! identity one) the cells of its transformed box, a triangle the cells of its vertices' box,
//! both sides of a cell boundary its box face lies on; planes mark none and leave the box
//! alone. And the grid picture comes out of both tracers identically.

mod common;

use std::path::Path;

use common::{assert_equivalent, render_both};
use whitted::grid::Grid;
use whitted::options::{DEFAULT_MAX_GRID_CELLS, GridOptions, GridView};
use whitted::output::{color_image, depth_image, normal_image};
use whitted::{RenderOptions, Scene};

fn scene(objects: &[&str]) -> Scene {
    let text = format!(
        "PerspectiveCamera {{ center 3 4 10 direction -3 -4 -10 up 0 1 0 angle 30 }}
         Lights {{ numLights 1 DirectionalLight {{ direction -0.5 -0.3 -1 color 0.7 0.7 0.7 }} }}
         Background {{ color 0.2 0 0.6 ambientLight 0.3 0.3 0.3 }}
         Materials {{ numMaterials 1 PhongMaterial {{ diffuseColor 1 1 1 }} }}
         Group {{ numObjects {} MaterialIndex 0 {} }}",
        objects.len(),
        objects.join("\n")
    );
    Scene::from_str(&text, Path::new("grid.txt")).unwrap()
}

/// The occupied cells of `g` as `(i, j, k, count)`.
fn occupied(g: &Grid) -> Vec<(u32, u32, u32, u32)> {
    let [nx, ny, nz] = g.cells;
    let mut out = Vec::new();
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let c = g.count([i, j, k]);
                if c > 0 {
                    out.push((i, j, k, c));
                }
            }
        }
    }
    out
}

#[test]
fn a_sphere_marks_the_cells_whose_centre_lies_within_its_radius() {
    // Radius 1 in a 5^3 grid over [-1, 1]^3: cell centres at 0, +-0.4, +-0.8, so a cell is
    // marked when i'^2 + j'^2 + k'^2 <= 6.25 with i' = i - 2 (and so on).
    let g = Grid::build(&scene(&["Sphere { center 0 0 0 radius 1 }"]), [5, 5, 5]);
    assert_eq!(g.bounds.unwrap().0.to_array(), [-1.0; 3]);
    let cells = occupied(&g);
    assert_eq!(cells.len(), 81);
    assert!(cells.iter().all(|c| c.3 == 1));
    let layer = |k: u32| -> Vec<(u32, u32)> {
        cells
            .iter()
            .filter(|c| c.2 == k)
            .map(|c| (c.0, c.1))
            .collect()
    };
    // The bottom layer (centres at z = -0.8): the 3x3 block in the middle.
    let block: Vec<(u32, u32)> = (1..4).flat_map(|j| (1..4).map(move |i| (i, j))).collect();
    assert_eq!(layer(0), block);
    // The middle layer: all 25 cells but the 4 corners (0.8^2 + 0.8^2 > 1).
    let middle = layer(2);
    assert_eq!(middle.len(), 21);
    for corner in [(0, 0), (4, 0), (0, 4), (4, 4)] {
        assert!(!middle.contains(&corner));
    }
    assert_eq!(layer(4), layer(0));
}

#[test]
fn a_sphere_under_a_transform_marks_its_box() {
    // The course's fallback when the sphere has a matrix, even the identity: the box.
    let g = Grid::build(
        &scene(&["Transform { Sphere { center 0 0 0 radius 1 } }"]),
        [5, 5, 5],
    );
    assert_eq!(occupied(&g).len(), 125);
    // Scaled: the box of the 8 transformed corners, [-2, 2] x [-1, 1] x [-1, 1].
    let g = Grid::build(
        &scene(&["Transform { Scale 2 1 1 Sphere { center 0 0 0 radius 1 } }"]),
        [4, 2, 2],
    );
    let (lo, hi) = g.bounds.unwrap();
    assert_eq!(
        (lo.to_array(), hi.to_array()),
        ([-2.0, -1.0, -1.0], [2.0, 1.0, 1.0])
    );
    assert_eq!(occupied(&g).len(), 16);
}

#[test]
fn a_triangle_marks_its_box_and_both_sides_of_a_boundary_it_lies_on() {
    // Scene 5_05: a unit sphere and two triangles in z = 0, in a 20x20x10 grid over
    // [-2, 2] x [-2, 2] x [-1, 1] (cells of 0.2). The upper triangle's box is
    // [-2, 2] x [0.4, 2] x [0, 0]: its bottom (y = 0.4) and its plane (z = 0) lie on cell
    // boundaries, so it marks i 0..19, j 11..19, k 4..5.
    let g = Grid::build(
        &scene(&[
            "Sphere { center 0 0 0 radius 1 }",
            "Triangle { vertex0 -2 0.4 0 vertex1 2 0.4 0 vertex2 0 2 0 }",
            "Triangle { vertex0 -2 -0.4 0 vertex1 0 -2 0 vertex2 2 -0.4 0 }",
        ]),
        [20, 20, 10],
    );
    let (lo, hi) = g.bounds.unwrap();
    assert_eq!(
        (lo.to_array(), hi.to_array()),
        ([-2.0, -2.0, -1.0], [2.0, 2.0, 1.0])
    );
    // Columns the sphere (x in [-1, 1], i in 5..=14) does not reach hold only triangle marks.
    let edge_columns: Vec<_> = occupied(&g)
        .into_iter()
        .filter(|c| c.0 < 5 || c.0 > 14)
        .collect();
    let upper: Vec<_> = edge_columns.iter().filter(|c| c.1 >= 10).collect();
    let lower: Vec<_> = edge_columns.iter().filter(|c| c.1 < 10).collect();
    // 10 columns x 9 rows x 2 layers for each triangle.
    assert_eq!((upper.len(), lower.len()), (180, 180));
    assert!(
        upper
            .iter()
            .all(|c| (11..=19).contains(&c.1) && (4..=5).contains(&c.2))
    );
    assert!(lower.iter().all(|c| c.1 <= 8 && (4..=5).contains(&c.2)));
    assert!(edge_columns.iter().all(|c| c.3 == 1));
    // In the middle, the sphere adds its cells: 2 where a triangle's cells overlap them.
    assert_eq!(g.count([9, 11, 4]), 2);
    assert_eq!(g.count([9, 11, 3]), 1);
    assert_eq!(g.stats().max_count, 2);
}

#[test]
fn planes_are_left_out_of_the_grid() {
    let g = Grid::build(
        &scene(&[
            "Plane { normal 0 1 0 offset -1 }",
            "Triangle { vertex0 0 0 0 vertex1 1 0 0 vertex2 0 1 1 }",
        ]),
        [2, 2, 2],
    );
    let (lo, hi) = g.bounds.unwrap();
    assert_eq!((lo.to_array(), hi.to_array()), ([0.0; 3], [1.0; 3]));
    let g = Grid::build(&scene(&["Plane { normal 0 1 0 offset -1 }"]), [2, 2, 2]);
    assert_eq!(g.bounds, None);
    assert!(occupied(&g).is_empty());
}

#[test]
fn both_tracers_draw_the_same_grid_pictures() {
    let scene = scene(&[
        "Sphere { center 0 0 0 radius 1 }",
        "Triangle { vertex0 -2 0.4 0 vertex1 2 0.4 0 vertex2 0 2 0 }",
        "Transform { Translate 1 -1 0.5 ZRotate 30 Scale 1 0.5 2 Sphere { center 0 0 0 radius 0.7 } }",
        "Plane { normal 0 1 0 offset -3 }",
    ]);
    for view in [GridView::Lit, GridView::Count] {
        let opts = RenderOptions {
            width: 96,
            height: 72,
            grid: Some(GridOptions {
                cells: [13, 9, 7],
                view: Some(view),
                max_cells: DEFAULT_MAX_GRID_CELLS,
            }),
            ..RenderOptions::default()
        };
        let (r, p) = render_both(&scene, &opts);
        assert_eq!(r.color, p.color, "{view:?}");
        assert_eq!(r.depth, p.depth, "{view:?}");
        assert_eq!(r.normal, p.normal, "{view:?}");
        assert_equivalent(&color_image(&r), &color_image(&p), "grid picture");
        assert_equivalent(
            &depth_image(&r, 5.0, 15.0),
            &depth_image(&p, 5.0, 15.0),
            "depth",
        );
        assert_equivalent(&normal_image(&r), &normal_image(&p), "normals");
        // Something is drawn, and so is the background.
        let bg = whitted::math::Vec3::new(0.2, 0.0, 0.6);
        assert!(r.color.iter().any(|&c| c != bg) && r.color.contains(&bg));
        assert_eq!(r.grid.unwrap().cells, [13, 9, 7]);
    }
}

#[test]
fn the_command_line_builds_the_grid_reports_it_and_draws_it() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = common::scratch_dir("grid_cli");
    let out = dir.join("g.png");
    let out = out.to_str().unwrap();
    // -grid alone: the normal render (the same bytes as without it), the grid in --stats.
    let plain = dir.join("plain.png");
    let run = common::whitted(
        root,
        &[
            "render",
            "scenes/glass_sphere.txt",
            "-o",
            plain.to_str().unwrap(),
            "--size",
            "48",
            "32",
        ],
    );
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    let run = common::whitted(
        root,
        &[
            "-input",
            "scenes/glass_sphere.txt",
            "-size",
            "48",
            "32",
            "-output",
            out,
            "-grid",
            "10",
            "10",
            "10",
            "-stats",
            "--specular-fix",
        ],
    );
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    assert_eq!(std::fs::read(out).unwrap(), std::fs::read(&plain).unwrap());
    let line = run
        .stderr
        .lines()
        .find(|l| l.starts_with("stats:"))
        .unwrap();
    assert!(
        line.contains(" grid=10x10x10 grid_cells=1000 grid_occupied="),
        "{line}"
    );
    assert!(
        run.stderr
            .contains("  grid     10x10x10 = 1,000 cells over "),
        "{}",
        run.stderr
    );
    // The picture, in both spellings and both views; the two views differ.
    let draw = |args: &[&str], file: &str| {
        let path = dir.join(file);
        let mut all = vec![
            "render",
            "scenes/glass_sphere.txt",
            "-o",
            path.to_str().unwrap(),
        ];
        all.extend_from_slice(&["--size", "48", "32"]);
        all.extend_from_slice(args);
        let run = common::whitted(root, &all);
        assert_eq!(run.code, Some(0), "{}", run.stderr);
        std::fs::read(path).unwrap()
    };
    let lit = draw(&["--grid", "6", "6", "6", "--visualize-grid"], "lit.png");
    assert_eq!(
        lit,
        draw(&["-grid", "6", "6", "6", "-visualize_grid"], "lit2.png")
    );
    let count = draw(
        &["--grid", "6", "6", "6", "--visualize-grid-count"],
        "count.png",
    );
    assert_ne!(lit, count);
    assert_ne!(lit, std::fs::read(&plain).unwrap());
    // Asking for a picture without a grid, or an empty or oversized grid, is a usage error.
    for (args, start) in [
        (
            vec!["--visualize-grid"],
            "option --visualize-grid needs -grid NX NY NZ",
        ),
        (
            vec!["--grid", "0", "4", "4"],
            "grid 0x4x4: expected at least 1 cell",
        ),
        (
            vec!["--grid", "300", "300", "300"],
            "grid 300x300x300 has 27000000 cells, over the limit of 16777216 (raise it \
             with --max-grid-cells N)",
        ),
    ] {
        let mut all = vec!["render", "scenes/glass_sphere.txt", "-o", out];
        all.extend_from_slice(&args);
        common::whitted(root, &all).assert_error(start);
    }
}
