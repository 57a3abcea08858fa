//! The command line: `whitted render`, `whitted bench` and the course's own command lines,
//! verbatim with `whitted` in place of `raytracer` (`whitted -input scene.txt -size 200 200
//! -output out.tga -shadows -bounces 10 -weight 0.01 -shade_back -gui`). `main` calls [`run`]
//! and turns its error into exit code 2; [`run`] picks the subcommand from [`COMMANDS`].
//!
//! Each subcommand's options are one table (`render_options.rs`: [`render::OPTIONS`], `bench.rs`:
//! [`bench::OPTIONS`]) of [`table::Opt`] entries: spellings (modern `--shade-back`, course
//! `-shade_back`, short `-o`), value names and descriptions, `--help` section and text, and a
//! handler. `table.rs` parses a command line through a table and prints the same table as
//! `--help`, so the two cannot drift apart; it also gives every table `-h`/`--help`, the nearest
//! spelling for a typo, and the refusal of an option given twice with different values.
//!
//! - **A new option**: one `Opt { .. }` entry in its command's table; its `apply` handler reads
//!   the values in order (`v.number()?`, `v.finite()?`, `v.path()?`, `v.choice(..)?`, each
//!   erring with the value's description) and stores them in the command's options struct
//!   (add the field there). Checks across options go in `render::check`.
//! - **A new subcommand** (`whitted merge`): a file `cli/merge.rs` with its options struct, its
//!   table, `parse_merge_args` and `help` (copy `bench.rs`), and one [`Subcommand`] entry in
//!   [`COMMANDS`] (its usage line joins `whitted --help`).
//!
//! ```text
//! args --run--> COMMANDS: render / course style --render::parse_render_args--> Command
//!                                  --execute.rs--> Scene::load, render, output, ray tree, stats
//!                         bench --bench::parse_bench_args--> BenchOptions --> crate::bench::run
//!                         tiles --tiles.rs--> one `render --tile I/N` line per tile + the merge line
//!                         merge --merge.rs--> crate::merge::merge
//! ```

pub mod bench;
mod execute;
pub mod merge;
pub mod render;
mod render_options;
mod sampling_options;
pub mod table;
pub mod tiles;

use std::ffi::OsString;

pub use bench::parse_bench_args;
pub use execute::execute;
pub use render::{Command, parse_args, parse_render_args};

use crate::error::{Error, Result};

/// A subcommand: its name, its usage lines for `whitted --help`, and what runs it on the
/// arguments after its name.
pub struct Subcommand {
    pub name: &'static str,
    pub usage: &'static str,
    pub run: fn(&[String]) -> Result<()>,
}

/// Every subcommand, in `whitted --help` order.
pub const COMMANDS: &[Subcommand] = &[
    Subcommand {
        name: "render",
        usage: render::USAGE,
        run: |args| match parse_render_args(args, true)? {
            Some(cmd) => execute(cmd),
            None => print_help(&render::help()),
        },
    },
    Subcommand {
        name: "bench",
        usage: bench::USAGE,
        run: |args| match parse_bench_args(args)? {
            Some(opts) => crate::bench::run(&opts),
            None => print_help(&bench::help()),
        },
    },
    Subcommand {
        name: "tiles",
        usage: tiles::USAGE,
        run: tiles::run,
    },
    Subcommand {
        name: "merge",
        usage: merge::USAGE,
        run: merge::run,
    },
];

/// The text of `whitted --help`: every subcommand's usage, then the render options (those of
/// the course's command lines too).
pub fn help() -> String {
    let usage: String = COMMANDS.iter().map(|c| c.usage).collect();
    let names: Vec<&str> = COMMANDS.iter().map(|c| c.name).collect();
    format!(
        "whitted: a Whitted-style ray tracer for the MIT 6.837 scene format\n\n\
         USAGE:\n{usage}    whitted COMMAND --help       the options of one command ({})\n\n{}",
        names.join(", "),
        render::options_help()
    )
}

fn print_help(text: &str) -> Result<()> {
    print!("{text}");
    Ok(())
}

/// Runs the program on `args` (including the program name).
pub fn run(args: Vec<OsString>) -> Result<()> {
    let args: Vec<String> = args
        .into_iter()
        .skip(1)
        .map(|a| {
            a.into_string()
                .map_err(|a| Error::Usage(format!("argument {a:?} is not valid UTF-8")))
        })
        .collect::<Result<_>>()?;
    match args.first().map(String::as_str) {
        None | Some("help" | "-h" | "--help" | "-help") => print_help(&help()),
        Some("-V" | "--version") => {
            println!("whitted {}", env!("CARGO_PKG_VERSION"));
            Ok(())
        }
        Some(a) if a.starts_with('-') => match parse_render_args(&args, false)? {
            Some(cmd) => execute(cmd),
            None => print_help(&render::help()),
        },
        Some(name) => match COMMANDS.iter().find(|c| c.name == name) {
            Some(command) => (command.run)(&args[1..]).map_err(|e| e.in_command(command.name)),
            None => Err(Error::Usage(format!(
                "unknown command `{name}`: expected {} or course options like -input",
                COMMANDS
                    .iter()
                    .map(|c| format!("`{}`", c.name))
                    .collect::<Vec<_>>()
                    .join(", ")
            ))),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::table::{Table, option_name};
    use super::*;

    /// No two options share a spelling, and an option's modern and course spellings name it
    /// alike (one option, two styles).
    fn check_table<T>(table: &Table<T>) {
        let mut names: Vec<String> = Vec::new();
        for opt in table.options {
            if !opt.long.is_empty() && !opt.course.is_empty() {
                assert_eq!(
                    option_name(opt.long),
                    option_name(opt.course),
                    "{}",
                    opt.long
                );
            }
            assert!(
                opt.long.starts_with("--") || opt.long.is_empty(),
                "{}",
                opt.long
            );
            assert!(!opt.course.starts_with("--"), "{}", opt.course);
            let mut own: Vec<String> = opt.spellings().filter_map(option_name).collect();
            own.dedup();
            for name in own {
                assert!(name != "help" && name != "h", "{name} is built in");
                assert!(!names.contains(&name), "{name}: two options spelled alike");
                names.push(name);
            }
            assert!(
                !opt.help.is_empty() && !opt.section.is_empty(),
                "{}",
                opt.name()
            );
        }
    }

    #[test]
    fn tables_are_consistent() {
        check_table(&render::OPTIONS);
        check_table(&bench::OPTIONS);
    }
}
