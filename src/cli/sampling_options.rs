//! The anti-aliasing options of `whitted render` and of the course's command lines
//! (assignment 7): the [`Opt`] entries ([`Entries`]) the table of `render_options.rs` lists
//! under [`SECTION`], what they record in [`Sampling`], and [`Sampling::resolve`], which turns
//! that into the render's sampler and filter once every option is read (the checks across
//! options: one sampler, one filter, `--sampler` with `--samples`, a perfect square for a
//! grid). The entries work on any command that has a [`Sampling`] and [`RenderOptions`]
//! ([`Sampled`]), so this file does not need `render_options.rs`.
//!
//! ```text
//! -uniform_samples N | -jittered_samples N | -random_samples N | --samples N [--sampler NAME]
//! -box_filter R | -tent_filter R | -gaussian_filter S | --filter box|tent|gaussian R
//! -render_samples FILE ZOOM, -render_filter FILE ZOOM, --seed N
//! ```

use std::marker::PhantomData;
use std::path::PathBuf;

use super::table::{Opt, Values};
use crate::error::{Error, Result};
use crate::filter::{Filter, Shape};
use crate::options::RenderOptions;
use crate::sampler::{Pattern, Sampler};

/// A command the anti-aliasing options fill.
pub trait Sampled {
    /// What the options asked for.
    fn sampling(&mut self) -> &mut Sampling;
    /// The render options (for the limits).
    fn render(&mut self) -> &mut RenderOptions;
}

/// The `--help` section of these options.
pub const SECTION: &str = "ANTI-ALIASING (assignment 7; defaults in brackets)";

/// What the anti-aliasing options asked for, before [`Sampling::resolve`] checks it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Sampling {
    /// A course sampler (`-jittered_samples 9`): the option, its pattern and count.
    pub course: Option<(String, Pattern, u32)>,
    /// `--samples N`.
    pub samples: Option<u32>,
    /// `--sampler NAME`.
    pub pattern: Option<Pattern>,
    /// The filter and the option that gave it.
    pub filter: Option<(String, Filter)>,
    /// `--seed N`.
    pub seed: Option<u64>,
    /// `-render_samples FILE ZOOM`.
    pub render_samples: Option<(PathBuf, u32)>,
    /// `-render_filter FILE ZOOM`.
    pub render_filter: Option<(PathBuf, u32)>,
}

impl Sampling {
    /// The sampler and the filter the options give, checked across options.
    pub fn resolve(&self) -> Result<(Sampler, Filter)> {
        let seed = self.seed.unwrap_or(crate::sampler::DEFAULT_SEED);
        let sampler = match (&self.course, self.samples, self.pattern) {
            (Some((option, pattern, count)), None, None) => check_square(option, *pattern, *count)?,
            (Some((option, ..)), Some(_), _) => return Err(two_samplers(option, "--samples")),
            (Some((option, ..)), None, Some(_)) => return Err(two_samplers(option, "--sampler")),
            (None, Some(count), pattern) => {
                check_square("--samples", pattern.unwrap_or(Pattern::Jittered), count)?
            }
            (None, None, Some(_)) => {
                return Err(Error::Usage(
                    "option --sampler needs --samples N to say how many samples".to_string(),
                ));
            }
            (None, None, None) => Sampler::default(),
        };
        let filter = self.filter.as_ref().map_or_else(Filter::default, |f| f.1);
        Ok((Sampler { seed, ..sampler }, filter))
    }
}

fn two_samplers(first: &str, second: &str) -> Error {
    Error::Usage(format!(
        "options {first} and {second}: expected one sampler, found two"
    ))
}

/// `pattern` with `count` samples, refused by `option` unless a grid pattern gets a square.
fn check_square(option: &str, pattern: Pattern, count: u32) -> Result<Sampler> {
    let sampler = Sampler {
        pattern,
        count,
        ..Sampler::default()
    };
    if pattern.needs_square() && sampler.grid() * sampler.grid() != count {
        return Err(Error::Usage(format!(
            "option {option}: {} sampling needs a perfect square count (1, 4, 9, 16, ...), \
             found {count}",
            pattern.name()
        )));
    }
    Ok(sampler)
}

/// Reads a sample count of at least 1.
fn count(v: &mut Values) -> Result<u32> {
    let n: u32 = v.number()?;
    if n == 0 {
        return Err(v.error("expected a sample count of at least 1, found 0"));
    }
    Ok(n)
}

/// The course sampler option `option`: records it, refusing a second, different one.
fn course_sampler<T: Sampled>(
    c: &mut T,
    v: &mut Values,
    option: &str,
    pattern: Pattern,
) -> Result<()> {
    let n = count(v)?;
    if let Some((first, ..)) = &c.sampling().course {
        if first != option {
            return Err(two_samplers(first, option));
        }
    }
    c.sampling().course = Some((option.to_string(), pattern, n));
    Ok(())
}

/// Reads a filter's radius or sigma: a positive number.
fn size(v: &mut Values, shape: Shape) -> Result<f32> {
    let s = v.finite()?;
    if s <= 0.0 {
        return Err(v.error(format_args!(
            "expected a positive {}, found {s}",
            shape.parameter()
        )));
    }
    Ok(s)
}

/// Records the filter `shape` of `size` given by `option`, refusing a second, different
/// filter option.
fn set_filter<T: Sampled>(c: &mut T, option: &str, shape: Shape, size: f32) -> Result<()> {
    if let Some((first, _)) = &c.sampling().filter {
        if first != option {
            return Err(Error::Usage(format!(
                "options {first} and {option}: expected one filter, found two"
            )));
        }
    }
    c.sampling().filter = Some((option.to_string(), Filter { shape, size }));
    Ok(())
}

/// The course filter option `option`.
fn course_filter<T: Sampled>(c: &mut T, v: &mut Values, option: &str, shape: Shape) -> Result<()> {
    let s = size(v, shape)?;
    set_filter(c, option, shape, s)
}

/// Reads a picture's file and zoom factor (at least 1).
fn picture(v: &mut Values) -> Result<(PathBuf, u32)> {
    let file = v.path()?;
    let zoom: u32 = v.number()?;
    if zoom == 0 {
        return Err(v.error("expected a zoom factor of at least 1, found 0"));
    }
    Ok((file, zoom))
}

/// The entries, for a command `T` (`Entries::<Command>::SAMPLES`).
pub struct Entries<T>(PhantomData<T>);

impl<T: Sampled + 'static> Entries<T> {
    pub const SAMPLES: Opt<T> = Opt {
        long: "--samples",
        course: "",
        short: "",
        values: &[("N", "a sample count")],
        section: SECTION,
        help: "N samples per pixel, jittered unless --sampler says otherwise [1, at the pixel \
               centre]. Without a filter, a pixel is the average of its own samples (a box of \
               radius 0.5). The depth and normal images are not filtered: a pixel shows the hit of \
               its sample nearest the centre, so a depth stays a distance to a surface that is \
               there; --ray-tree follows that sample too",
        apply: |c, v| {
            let n = count(v)?;
            c.sampling().samples = Some(n);
            Ok(())
        },
    };

    pub const SAMPLER: Opt<T> = Opt {
        long: "--sampler",
        course: "",
        short: "",
        values: &[(
            "uniform|random|jittered",
            "`uniform`, `random` or `jittered`",
        )],
        section: SECTION,
        help: "with --samples: where the samples lie: the centres of a k x k grid of cells \
               (uniform, N = k*k), anywhere in the pixel (random), one anywhere in each cell \
               (jittered, N = k*k) [jittered]",
        apply: |c, v| {
            c.sampling().pattern = Some(v.choice(Pattern::from_name)?);
            Ok(())
        },
    };

    pub const UNIFORM_SAMPLES: Opt<T> = Opt {
        long: "",
        course: "-uniform_samples",
        short: "",
        values: &[("N", "a sample count")],
        section: SECTION,
        help: "the course's --samples N --sampler uniform",
        apply: |c, v| course_sampler(c, v, "-uniform_samples", Pattern::Uniform),
    };

    pub const JITTERED_SAMPLES: Opt<T> = Opt {
        long: "",
        course: "-jittered_samples",
        short: "",
        values: &[("N", "a sample count")],
        section: SECTION,
        help: "the course's --samples N --sampler jittered",
        apply: |c, v| course_sampler(c, v, "-jittered_samples", Pattern::Jittered),
    };

    pub const RANDOM_SAMPLES: Opt<T> = Opt {
        long: "",
        course: "-random_samples",
        short: "",
        values: &[("N", "a sample count")],
        section: SECTION,
        help: "the course's --samples N --sampler random",
        apply: |c, v| course_sampler(c, v, "-random_samples", Pattern::Random),
    };

    pub const SEED: Opt<T> = Opt {
        long: "--seed",
        course: "",
        short: "",
        values: &[("N", "a seed (a whole number)")],
        section: SECTION,
        help: "changes every random and jittered sample's place; a sample's place is a hash of its \
               pixel, its index and the seed, so it does not depend on threads or tiles [0]",
        apply: |c, v| {
            c.sampling().seed = Some(v.number()?);
            Ok(())
        },
    };

    pub const FILTER: Opt<T> = Opt {
        long: "--filter",
        course: "",
        short: "",
        values: &[
            ("box|tent|gaussian", "`box`, `tent` or `gaussian`"),
            ("R", "a filter radius or sigma"),
        ],
        section: SECTION,
        help: "make each pixel the weighted average of the samples of the pixels around it, the \
               weights normalised (at the border over the pixels inside the image): box R: 1 within \
               R of the centre on both axes; tent R: 1 - d/R; gaussian R: exp(-d^2 / 2R^2) with R \
               the standard deviation. Only the pixels within ceil(R - 1/2) (Gaussian: ceil(2R - \
               1/2)) count, as in the course; the Gaussian is not cut at 2R inside them. A pixel \
               whose weights are all zero is black [box 0.5]",
        apply: |c, v| {
            let shape = v.choice(Shape::from_name)?;
            let s = size(v, shape)?;
            set_filter(c, "--filter", shape, s)
        },
    };

    pub const BOX_FILTER: Opt<T> = Opt {
        long: "",
        course: "-box_filter",
        short: "",
        values: &[("R", "a filter radius")],
        section: SECTION,
        help: "the course's --filter box R",
        apply: |c, v| course_filter(c, v, "-box_filter", Shape::Box),
    };

    pub const TENT_FILTER: Opt<T> = Opt {
        long: "",
        course: "-tent_filter",
        short: "",
        values: &[("R", "a filter radius")],
        section: SECTION,
        help: "the course's --filter tent R",
        apply: |c, v| course_filter(c, v, "-tent_filter", Shape::Tent),
    };

    pub const GAUSSIAN_FILTER: Opt<T> = Opt {
        long: "",
        course: "-gaussian_filter",
        short: "",
        values: &[("SIGMA", "a filter sigma")],
        section: SECTION,
        help: "the course's --filter gaussian SIGMA",
        apply: |c, v| course_filter(c, v, "-gaussian_filter", Shape::Gaussian),
    };

    pub const RENDER_SAMPLES: Opt<T> = Opt {
        long: "--render-samples",
        course: "-render_samples",
        short: "",
        values: &[("FILE", "a file name"), ("ZOOM", "a zoom factor")],
        section: SECTION,
        help: "also write the samples, zoomed ZOOM times: a grey and black checkerboard of the \
               pixels with one dot per sample, in its colour, where it lies in its pixel (for small \
               images: the picture is ZOOM^2 times the image)",
        apply: |c, v| {
            c.sampling().render_samples = Some(picture(v)?);
            Ok(())
        },
    };

    pub const RENDER_FILTER: Opt<T> = Opt {
        long: "--render-filter",
        course: "-render_filter",
        short: "",
        values: &[("FILE", "a file name"), ("ZOOM", "a zoom factor")],
        section: SECTION,
        help: "also write the filter, zoomed ZOOM times: the weight each point of the pixels around \
               the centre pixel gets towards it, in grey (not normalised: 1 is white), the pixel \
               grid in blue, dark blue beyond the filter's pixels; needs no rendering",
        apply: |c, v| {
            c.sampling().render_filter = Some(picture(v)?);
            Ok(())
        },
    };

    pub const MAX_SAMPLES: Opt<T> = Opt {
        long: "--max-samples",
        course: "",
        short: "",
        values: &[("N", "a sample count")],
        section: SECTION,
        help: "refuse more samples per pixel [1024]",
        apply: |c, v| {
            c.render().max_samples = v.number()?;
            Ok(())
        },
    };

    pub const MAX_FILTER_RADIUS: Opt<T> = Opt {
        long: "--max-filter-radius",
        course: "",
        short: "",
        values: &[("N", "a radius in pixels")],
        section: SECTION,
        help: "refuse filters reaching more than N pixels from the centre [32]",
        apply: |c, v| {
            c.render().max_filter_radius = v.number()?;
            Ok(())
        },
    };
}
