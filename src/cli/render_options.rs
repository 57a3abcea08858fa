//! The options of `whitted render` and of the course's command lines: the [`Command`] they
//! fill and the table [`OPTIONS`] (spellings, values, help, handler) that fills it, in
//! `--help` order. `render.rs` runs command lines through it and checks the result.

use std::path::PathBuf;

use super::sampling_options::{Entries, Sampled, Sampling};
use super::table::{Opt, Table, Values};
use crate::error::Result;
use crate::math::Vec3;
use crate::options::{self, GridView, RenderOptions, Tracer, Window};
use crate::witness::{WitnessPlace, WitnessSpec};

/// Everything the command line asks for.
#[derive(Clone, Debug, PartialEq)]
pub struct Command {
    /// The scene file (empty until `-input` or the positional argument gives it).
    pub scene: PathBuf,
    pub output: Option<PathBuf>,
    pub depth: Option<(f32, f32, PathBuf)>,
    pub normals: Option<PathBuf>,
    pub render: RenderOptions,
    pub stats: bool,
    /// `--ray-tree X Y FILE.json`: the pixel whose ray tree to write, and where.
    pub ray_tree: Option<(u32, u32, PathBuf)>,
    /// `--ray-tree-image FILE`: the witness picture of that tree.
    pub ray_tree_image: Option<PathBuf>,
    /// Where the witness camera of the picture stands.
    pub witness: WitnessSpec,
    /// `--heatmap FILE`: the eye rays' traversal cost picture.
    pub heatmap: Option<PathBuf>,
    /// `--smooth-normals`: give meshes without normals area-weighted vertex normals.
    pub smooth_normals: bool,
    /// `--grid NX NY NZ`: the course's grid, cells per axis.
    pub grid: Option<[u32; 3]>,
    /// `--visualize-grid` or `--visualize-grid-count`, with the spelling typed (for errors).
    pub grid_view: Option<(GridView, String)>,
    /// `--max-grid-cells N`.
    pub max_grid_cells: u64,
    /// Notes for stderr about accepted-but-inert options.
    pub notes: Vec<String>,
    /// `--tile I/N`, turned into `render.crop` once the image size is known.
    pub tile: Option<(u32, u32)>,
    /// The anti-aliasing options as given (`render` holds the sampler and filter they make).
    pub sampling: Sampling,
}

impl Command {
    /// Nothing asked yet: the defaults of the modern command (`modern`) or of the course's.
    pub(super) fn new(modern: bool) -> Command {
        let mut render = RenderOptions::default();
        // The course's command lines reproduce the handout images, which clamp the specular
        // term without the lecture's fix; the modern command uses the fix.
        render.shade.specular_fix = modern;
        Command {
            scene: PathBuf::new(),
            output: None,
            depth: None,
            normals: None,
            render,
            stats: false,
            ray_tree: None,
            ray_tree_image: None,
            witness: WitnessSpec::default(),
            heatmap: None,
            smooth_normals: false,
            grid: None,
            grid_view: None,
            max_grid_cells: options::DEFAULT_MAX_GRID_CELLS,
            notes: Vec::new(),
            tile: None,
            sampling: Sampling::default(),
        }
    }
}

impl Sampled for Command {
    fn sampling(&mut self) -> &mut Sampling {
        &mut self.sampling
    }

    fn render(&mut self) -> &mut RenderOptions {
        &mut self.render
    }
}

const FILES: &str =
    "INPUT AND OUTPUT (images by extension: .png .tga .ppm 8-bit, .exr .pfm .hdr float)";
const PIECES: &str = "PIECES OF A BIG RENDER (docs/render-farm.md, whitted tiles, whitted merge)";
const RENDERING: &str = "RENDERING (defaults in brackets)";
const RAY_TREE: &str = "RAY TREE (every ray one pixel spawns; -o is optional with it)";
const GRID: &str =
    "GRID (the course's uniform grid, assignments 5-6; whitted still renders with its BVH)";
const COURSE: &str = "COURSE OPTIONS (single dash, as in the handouts)";

/// The extensions of image files, refused as ray-tree JSON paths.
const IMAGE_EXTENSIONS: [&str; 15] = [
    "png", "tga", "ppm", "pgm", "pbm", "pnm", "pfm", "exr", "hdr", "jpg", "jpeg", "bmp", "gif",
    "tif", "tiff",
];

/// The note an option of the course's OpenGL preview leaves.
fn no_preview(c: &mut Command, v: &mut Values) -> Result<()> {
    c.notes.push(format!(
        "note: {} ignored: whitted has no OpenGL preview",
        v.option()
    ));
    Ok(())
}

/// Every option of `whitted render` and of the course's command lines, in `--help` order.
/// A new option is one entry here (its handler stores its values in the [`Command`]).
pub static OPTIONS: Table<Command> = Table {
    unknown: "unknown option",
    options: &[
        Opt {
            long: "--input",
            course: "-input",
            short: "-i",
            values: &[("SCENE", "a file name")],
            section: FILES,
            help: "the scene file (`whitted render` also takes it as its first argument)",
            apply: |c, v| {
                c.scene = v.path()?;
                Ok(())
            },
        },
        Opt {
            long: "--output",
            course: "-output",
            short: "-o",
            values: &[("FILE", "a file name")],
            section: FILES,
            help: "colour image: 8-bit int(c * 255); float formats linear, as rendered (EXR: \
                   32-bit, ZIP, channels R G B; HDR: RGBE)",
            apply: |c, v| {
                c.output = Some(v.path()?);
                Ok(())
            },
        },
        Opt {
            long: "--depth",
            course: "-depth",
            short: "",
            values: &[
                ("NEAR", "a near distance"),
                ("FAR", "a far distance"),
                ("FILE", "a file name"),
            ],
            section: FILES,
            help: "depth image: white at NEAR, black at FAR and beyond (NEAR < FAR); float formats \
                   hold the distance along the primary ray (+inf where nothing is hit, HDR 0; EXR \
                   channel Z)",
            apply: |c, v| {
                let near = v.finite()?;
                let far = v.finite()?;
                if near >= far {
                    return Err(v.error(format_args!(
                        "expected a near distance below the far distance, found {near} and {far}"
                    )));
                }
                c.depth = Some((near, far, v.path()?));
                Ok(())
            },
        },
        Opt {
            long: "--normals",
            course: "-normals",
            short: "",
            values: &[("FILE", "a file name")],
            section: FILES,
            help: "normal image: abs(normal) as RGB; float formats the signed normal x y z (HDR \
                   abs)",
            apply: |c, v| {
                c.normals = Some(v.path()?);
                Ok(())
            },
        },
        Opt {
            long: "--heatmap",
            course: "",
            short: "",
            values: &[("FILE", "a file name")],
            section: FILES,
            help: "the packet tracer's cost per eye ray (BVH nodes entered plus primitives \
                   tested) as a colour map, black (0) to pale yellow (the maximum), with its \
                   scale in a strip below; the maximum and its pixel are printed on stderr",
            apply: |c, v| {
                c.heatmap = Some(v.path()?);
                Ok(())
            },
        },
        Opt {
            long: "--size",
            course: "-size",
            short: "",
            values: &[("W", "a width in pixels"), ("H", "a height in pixels")],
            section: RENDERING,
            help: "image size [512 512]",
            apply: |c, v| {
                c.render.width = v.number()?;
                c.render.height = v.number()?;
                Ok(())
            },
        },
        Opt {
            long: "--shadows",
            course: "-shadows",
            short: "",
            values: &[],
            section: RENDERING,
            help: "cast shadow rays [off]",
            apply: |c, _| {
                c.render.shade.shadows = true;
                Ok(())
            },
        },
        Opt {
            long: "--bounces",
            course: "-bounces",
            short: "",
            values: &[("N", "a bounce count")],
            section: RENDERING,
            help: "maximum mirror/refraction depth [5]",
            apply: |c, v| {
                c.render.shade.bounces = v.number()?;
                Ok(())
            },
        },
        Opt {
            long: "--weight",
            course: "-weight",
            short: "",
            values: &[("W", "a weight")],
            section: RENDERING,
            help: "skip rays whose contribution weight is below W [0.01]",
            apply: |c, v| {
                c.render.shade.weight = v.finite()?;
                Ok(())
            },
        },
        Opt {
            long: "--shade-back",
            course: "-shade_back",
            short: "",
            values: &[],
            section: RENDERING,
            help: "shade back faces (flip their normal) [off: back faces are black]",
            apply: |c, _| {
                c.render.shade.shade_back = true;
                Ok(())
            },
        },
        Opt {
            long: "--specular-fix",
            course: "",
            short: "",
            values: &[],
            section: RENDERING,
            help: "scale the specular term by max(n.l, 0), the lecture's fix [on for `whitted \
                   render`]",
            apply: |c, _| {
                c.render.shade.specular_fix = true;
                Ok(())
            },
        },
        Opt {
            long: "--no-specular-fix",
            course: "",
            short: "",
            values: &[],
            section: RENDERING,
            help: "only clamp the specular term to 0 where n.l <= 0, as the handout images do \
                   [on for course-style command lines]",
            apply: |c, _| {
                c.render.shade.specular_fix = false;
                Ok(())
            },
        },
        Opt {
            long: "--transparent-shadows",
            course: "",
            short: "",
            values: &[],
            section: RENDERING,
            help: "tint shadows by the transparent colour of occluders [off]",
            apply: |c, _| {
                c.render.shade.transparent_shadows = true;
                Ok(())
            },
        },
        Opt {
            long: "--fresnel",
            course: "",
            short: "",
            values: &[],
            section: RENDERING,
            help: "Schlick Fresnel split of transparent colour [off]",
            apply: |c, _| {
                c.render.shade.fresnel = true;
                Ok(())
            },
        },
        Opt {
            long: "--smooth-normals",
            course: "",
            short: "",
            values: &[],
            section: RENDERING,
            help: "shade meshes without vertex normals (`vn`) smoothly, with area-weighted \
                   vertex normals [off: flat; meshes with vn are always smooth]",
            apply: |c, _| {
                c.smooth_normals = true;
                Ok(())
            },
        },
        Opt {
            long: "--tracer",
            course: "",
            short: "",
            values: &[("reference|packet", "`reference` or `packet`")],
            section: RENDERING,
            help: "which tracer renders [packet]",
            apply: |c, v| {
                c.render.tracer = v.choice(Tracer::from_name)?;
                Ok(())
            },
        },
        Opt {
            long: "--threads",
            course: "",
            short: "",
            values: &[("N", "a thread count")],
            section: RENDERING,
            help: "worker threads [all cores]; output is identical for any N",
            apply: |c, v| {
                c.render.threads = v.number()?;
                Ok(())
            },
        },
        Opt {
            long: "--max-pixels",
            course: "",
            short: "",
            values: &[("N", "a pixel count")],
            section: RENDERING,
            help: "refuse renders of more pixels (a crop counts its own) [67108864]",
            apply: |c, v| {
                c.render.max_pixels = v.number()?;
                Ok(())
            },
        },
        Opt {
            long: "--max-bounces",
            course: "",
            short: "",
            values: &[("N", "a bounce count")],
            section: RENDERING,
            help: "refuse larger bounce counts [1000]",
            apply: |c, v| {
                c.render.max_bounces = v.number()?;
                Ok(())
            },
        },
        Opt {
            long: "--stats",
            course: "-stats",
            short: "",
            values: &[],
            section: RENDERING,
            help: "print ray counts by kind and bounce, time per phase, Mrays/s and peak memory \
                   to stderr, then one `stats: key=value ...` line (a progress bar shows on \
                   stderr, only when it is a terminal, for renders over a second)",
            apply: |c, _| {
                c.stats = true;
                Ok(())
            },
        },
        Opt {
            long: "--crop",
            course: "",
            short: "",
            values: &[
                ("X0", "a first column X0"),
                ("X1", "an end column X1"),
                ("Y0", "a first row Y0"),
                ("Y1", "an end row Y1"),
            ],
            section: PIECES,
            help: "render only columns X0..X1 and rows Y0..Y1 (half-open, in the full image), with \
                   exactly the rays the full render traces there",
            apply: |c, v| {
                let (x0, x1, y0, y1) = (v.number()?, v.number()?, v.number()?, v.number()?);
                c.render.crop = Some(Window { x0, x1, y0, y1 });
                Ok(())
            },
        },
        Opt {
            long: "--tile",
            course: "",
            short: "",
            values: &[("I/N", "a tile I/N such as 3/16")],
            section: PIECES,
            help: "render tile I (from 0) of N: horizontal strips of whole rows, top to bottom, cut \
                   on multiples of 8 rows as evenly as they go (strip I takes runs floor(I*R/N) to \
                   floor((I+1)*R/N) of the R = ceil(H/8) runs of 8 rows). A piece records its \
                   place in the full image and its render's fingerprint: an EXR in its data \
                   window and an attribute, other formats in a sidecar FILE.piece",
            apply: |c, v| {
                c.tile = Some(v.choice(|t| {
                    let (i, n) = t.split_once('/')?;
                    Some((i.parse().ok()?, n.parse().ok()?))
                })?);
                Ok(())
            },
        },
        Entries::<Command>::SAMPLES,
        Entries::<Command>::SAMPLER,
        Entries::<Command>::UNIFORM_SAMPLES,
        Entries::<Command>::JITTERED_SAMPLES,
        Entries::<Command>::RANDOM_SAMPLES,
        Entries::<Command>::SEED,
        Entries::<Command>::FILTER,
        Entries::<Command>::BOX_FILTER,
        Entries::<Command>::TENT_FILTER,
        Entries::<Command>::GAUSSIAN_FILTER,
        Entries::<Command>::RENDER_SAMPLES,
        Entries::<Command>::RENDER_FILTER,
        Entries::<Command>::MAX_SAMPLES,
        Entries::<Command>::MAX_FILTER_RADIUS,
        Opt {
            long: "--ray-tree",
            course: "",
            short: "",
            values: &[
                ("X", "a pixel column X"),
                ("Y", "a pixel row Y"),
                ("FILE.json", "a file name"),
            ],
            section: RAY_TREE,
            help: "trace pixel (X, Y) again after the render (x from the left, y from the top, \
                   as in the image) and write its tree: per segment the kind (eye, shadow, \
                   reflected, transmitted), parent, depth, weight, origin, end, primitive and \
                   material hit, light, blocked. Ends: the hit point; the point light; for a \
                   blocked shadow ray its nearest occluder; for escaping rays and shadow rays \
                   to directional lights, 100 units along the ray",
            apply: |c, v| {
                let x = v.number()?;
                let y = v.number()?;
                let json = v.path()?;
                let ext = json.extension().and_then(|e| e.to_str());
                if let Some(ext) = ext.filter(|e| IMAGE_EXTENSIONS.contains(&&*e.to_lowercase())) {
                    return Err(v.error(format_args!(
                        "expected a JSON file name, found `{}`, an image name (.{ext}); the \
                         picture of the tree goes to --ray-tree-image",
                        json.display()
                    )));
                }
                c.ray_tree = Some((x, y, json));
                Ok(())
            },
        },
        Opt {
            long: "--ray-tree-image",
            course: "",
            short: "",
            values: &[("FILE.png", "a file name")],
            section: RAY_TREE,
            help: "with --ray-tree: the scene seen by a witness camera, same size as the image, \
                   with the tree drawn over it: eye gray, shadow green (blocked: dashed dark \
                   green, X at the occluder), reflected red, transmitted blue, the main camera \
                   a white frustum, point lights yellow; parts hidden behind surfaces are drawn \
                   fainter; planes and lone triangles the witness sees from behind are left out \
                   (to look into rooms)",
            apply: |c, v| {
                c.ray_tree_image = Some(v.path()?);
                Ok(())
            },
        },
        Opt {
            long: "--witness-orbit",
            course: "",
            short: "",
            values: &[
                ("YAW", "a yaw angle in degrees"),
                ("PITCH", "a pitch angle in degrees"),
            ],
            section: RAY_TREE,
            help: "default witness placement: it looks at the eye ray's first hit from the main \
                   camera's side turned YAW degrees about the vertical axis (positive: to the \
                   right) and raised PITCH degrees, as near as keeps the main camera and the \
                   tree's hits in view [40 20]",
            apply: |c, v| {
                let yaw_deg = v.finite()?;
                let pitch_deg = v.finite()?;
                c.witness.place = WitnessPlace::Orbit { yaw_deg, pitch_deg };
                Ok(())
            },
        },
        Opt {
            long: "--witness-camera",
            course: "",
            short: "",
            values: &[
                ("CX", "coordinate CX"),
                ("CY", "coordinate CY"),
                ("CZ", "coordinate CZ"),
                ("LX", "coordinate LX"),
                ("LY", "coordinate LY"),
                ("LZ", "coordinate LZ"),
            ],
            section: RAY_TREE,
            help: "place the witness camera at C looking at L instead",
            apply: |c, v| {
                let center = Vec3::new(v.finite()?, v.finite()?, v.finite()?);
                let look_at = Vec3::new(v.finite()?, v.finite()?, v.finite()?);
                if center == look_at {
                    return Err(v.error("expected a look-at point different from the position"));
                }
                c.witness.place = WitnessPlace::At { center, look_at };
                Ok(())
            },
        },
        Opt {
            long: "--witness-angle",
            course: "",
            short: "",
            values: &[("DEG", "a field of view in degrees")],
            section: RAY_TREE,
            help: "witness field of view [60]",
            apply: |c, v| {
                let a = v.finite()?;
                if !(a > 0.0 && a < 180.0) {
                    return Err(v.error(format_args!(
                        "expected a field of view between 0 and 180 degrees, found {a}"
                    )));
                }
                c.witness.angle_deg = a;
                Ok(())
            },
        },
        Opt {
            long: "--grid",
            course: "-grid",
            short: "",
            values: &[
                ("NX", "cells along x"),
                ("NY", "cells along y"),
                ("NZ", "cells along z"),
            ],
            section: GRID,
            help: "build the course's uniform grid over the scene's bounded primitives (planes \
                   stay outside); --stats adds its size, box and occupied cells",
            apply: |c, v| {
                c.grid = Some([v.number()?, v.number()?, v.number()?]);
                Ok(())
            },
        },
        Opt {
            long: "--visualize-grid",
            course: "-visualize_grid",
            short: "",
            values: &[],
            section: GRID,
            help: "with --grid: draw the occupied cells instead of the scene, each the colour of \
                   its primitive count (1 white, 2 magenta, 5 blue, 8 cyan, 11 green, 14 yellow, \
                   17+ red) shaded by the scene's lights",
            apply: |c, v| {
                c.grid_view = Some((GridView::Lit, v.option().to_string()));
                Ok(())
            },
        },
        Opt {
            long: "--visualize-grid-count",
            course: "-visualize_grid_count",
            short: "",
            values: &[],
            section: GRID,
            help: "with --grid: the same cells in their count's colour, unlit, so counts read \
                   exactly",
            apply: |c, v| {
                c.grid_view = Some((GridView::Count, v.option().to_string()));
                Ok(())
            },
        },
        Opt {
            long: "--max-grid-cells",
            course: "",
            short: "",
            values: &[("N", "a cell count")],
            section: GRID,
            help: "refuse larger grids [16777216]",
            apply: |c, v| {
                c.max_grid_cells = v.number()?;
                Ok(())
            },
        },
        Opt {
            long: "",
            course: "-gui",
            short: "",
            values: &[],
            section: COURSE,
            help: "accepted with a note: whitted has no OpenGL preview",
            apply: no_preview,
        },
        Opt {
            long: "",
            course: "-tessellation",
            short: "",
            values: &[("THETA", "theta steps"), ("PHI", "phi steps")],
            section: COURSE,
            help: "accepted with a note (the preview's sphere tessellation)",
            apply: |c, v| {
                let _: u32 = v.number()?;
                let _: u32 = v.number()?;
                no_preview(c, v)
            },
        },
        Opt {
            long: "",
            course: "-gouraud",
            short: "",
            values: &[],
            section: COURSE,
            help: "accepted with a note (the preview's smooth shading)",
            apply: no_preview,
        },
    ],
};
