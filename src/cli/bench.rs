//! `whitted bench`: its option table [`OPTIONS`], [`parse_bench_args`] which reads a command
//! line into the [`BenchOptions`] that `crate::bench::run` takes, and its help text.

use super::table::{self, Opt, Parsed, Table};
use crate::bench::{self, BenchOptions, BenchScene};
use crate::error::Result;

const SECTION: &str = "OPTIONS (defaults in brackets)";

/// Every option of `whitted bench`. A new option is one entry here.
pub static OPTIONS: Table<BenchOptions> = Table {
    unknown: "bench: unknown option",
    options: &[
        Opt {
            long: "--scene",
            course: "",
            short: "",
            values: &[("NAME|all", "a scene name or `all`")],
            section: SECTION,
            help: "spheres64, spheres4096, torus100k, torus1m or all [all]",
            apply: |o, v| {
                let name = v.text()?;
                o.scenes = if name == "all" {
                    BenchScene::ALL.to_vec()
                } else {
                    vec![BenchScene::from_name(name).ok_or_else(|| {
                        v.error(format_args!(
                            "expected one of spheres64, spheres4096, torus100k, torus1m or \
                             all, found `{name}`"
                        ))
                    })?]
                };
                Ok(())
            },
        },
        Opt {
            long: "--threads",
            course: "",
            short: "",
            values: &[("N", "a thread count")],
            section: SECTION,
            help: "worker threads tracing the rays; 0 means all cores [1]",
            apply: |o, v| {
                o.threads = v.number()?;
                Ok(())
            },
        },
        Opt {
            long: "--reps",
            course: "",
            short: "",
            values: &[("N", "a repetition count")],
            section: SECTION,
            help: "repetitions; each figure is the best of them [3]",
            apply: |o, v| {
                o.reps = v.number()?;
                if !(1..=1000).contains(&o.reps) {
                    return Err(v.error(format_args!(
                        "expected 1 to 1000 repetitions, found {}",
                        o.reps
                    )));
                }
                Ok(())
            },
        },
        Opt {
            long: "--width",
            course: "",
            short: "",
            values: &[("W", "a width in pixels")],
            section: SECTION,
            help: "image width, a multiple of 4 [1024]",
            apply: |o, v| {
                o.width = v.number()?;
                Ok(())
            },
        },
        Opt {
            long: "--height",
            course: "",
            short: "",
            values: &[("H", "a height in pixels")],
            section: SECTION,
            help: "image height, a multiple of 2 [1024]",
            apply: |o, v| {
                o.height = v.number()?;
                Ok(())
            },
        },
    ],
};

/// The usage line of `whitted bench`, shared with the overview of `whitted --help`.
pub const USAGE: &str =
    "    whitted bench [OPTIONS]      ray throughput; see `whitted bench --help`\n";

/// The text of `whitted bench --help`.
pub fn help() -> String {
    format!(
        "whitted bench: ray throughput on the four procedural scenes of shared/bench/SCENES.md\n\n\
         USAGE:\n    whitted bench [OPTIONS]\n\n{}\
         Prints `CSV,<scene>,<kernel>,<rays>,<hits>,<ms>,<Mrays/s>` per kernel (primary, shadow, \
         mirror,\ndiffuse: 8-ray packets; the same with `_scalar`: one ray at a time) and\n\
         `CSV,<scene>,build_1t_ms,<primitives>,0,<ms>,<Mprims/s>` for the BVH build on one \
         thread.\n",
        table::help(&OPTIONS)
    )
}

/// Parses the arguments after `bench`; `None` asks for the help text.
pub fn parse_bench_args(args: &[String]) -> Result<Option<BenchOptions>> {
    let mut opts = BenchOptions::default();
    if table::parse(&OPTIONS, args, &mut opts, None)? == Parsed::Help {
        return Ok(None);
    }
    bench::check_size(opts.width, opts.height)?;
    Ok(Some(opts))
}
