//! `whitted tiles N SCENE [render options] -o OUT`: the command lines of a render split into
//! `N` tiles, for any scheduler to run ([`run`] checks the render's options parse and leave
//! room for `N` tiles, [`tile_lines`] writes the lines). It prints one `whitted render ... --tile I/N` line per
//! tile, in which each output file (`-o`, `--depth`'s, `--normals`') is renamed to that tile's
//! piece (`OUT` = `big.exr` gives `big.tile00.exr`, `big.tile01.exr`, ...; as many digits as
//! `N - 1` has), and last one line of `whitted merge` commands (joined by `&&`, one per output)
//! that assemble the pieces. So
//!
//! ```text
//! whitted tiles 16 scene.txt --size 1024 768 -o big.exr > jobs.txt
//! head -n 16 jobs.txt | parallel && tail -n 1 jobs.txt | sh
//! ```
//!
//! renders the frame on every core of a machine (or, with `parallel -S host1,host2`, over ssh
//! hosts that share the folder). Lines name the program as it was called, and quote for a POSIX
//! shell whatever needs it.

use std::io::Write as _;
use std::path::{Path, PathBuf};

use super::render::parse_args;
use super::table::option_name;
use crate::error::{Error, Result};
use crate::options::Window;

/// The usage line of `whitted tiles`, for `whitted --help`.
pub const USAGE: &str =
    "    whitted tiles N SCENE ...    the render lines of N tiles, then their merge\n";

/// The text of `whitted tiles --help`.
pub fn help() -> String {
    format!(
        "whitted tiles: the command lines of a render cut into N tiles, for any scheduler\n\n\
         USAGE:\n{USAGE}\n\
         The arguments after N are those of `whitted render` (see `whitted render --help`),\n\
         without --crop, --tile and --ray-tree. Prints N lines `whitted render ... --tile I/N`\n\
         whose outputs are the tiles' pieces (OUT = big.exr: big.tile00.exr, ...), then one\n\
         line of `whitted merge` commands. Run the first N lines with any scheduler, then the\n\
         last:\n\n\
         \x20   whitted tiles 16 scene.txt --size 4096 3072 -o big.exr > jobs.txt\n\
         \x20   head -n 16 jobs.txt | parallel && tail -n 1 jobs.txt | sh\n\n\
         See docs/render-farm.md (GNU parallel over ssh, Slurm, Kubernetes).\n"
    )
}

/// `whitted tiles N [render arguments]`: checks and prints the lines.
pub fn run(args: &[String]) -> Result<()> {
    if matches!(
        args.first().map(String::as_str),
        Some("-h" | "--help" | "-help")
    ) {
        print!("{}", help());
        return Ok(());
    }
    let count: u32 = args
        .first()
        .and_then(|n| n.parse().ok())
        .filter(|&n| n > 0)
        .ok_or_else(|| {
            Error::Usage(format!(
                "expected a tile count of at least 1: whitted tiles N SCENE -o OUT, found {}",
                args.first()
                    .map_or("nothing".to_string(), |a| format!("`{a}`"))
            ))
        })?;
    let rest = &args[1..];
    let modern = rest.first().is_some_and(|a| option_name(a).is_none());
    let cmd = parse_args(rest, modern)?;
    Window::tile(0, count, cmd.render.width, cmd.render.height)?;
    let exe = std::env::args()
        .next()
        .unwrap_or_else(|| "whitted".to_string());
    let mut stdout = std::io::stdout().lock();
    for line in tile_lines(&exe, count, rest)? {
        writeln!(stdout, "{line}").map_err(|e| Error::io(Path::new("stdout"), "write", e))?;
    }
    Ok(())
}

/// The piece of output `out` that tile `index` of `count` writes.
pub fn piece_path(out: &Path, index: u32, count: u32) -> PathBuf {
    let digits = count.saturating_sub(1).max(1).ilog10() as usize + 1;
    let stem = out
        .file_stem()
        .map_or_else(String::new, |s| s.to_string_lossy().into_owned());
    let name = match out.extension() {
        Some(ext) => format!("{stem}.tile{index:0digits$}.{}", ext.to_string_lossy()),
        None => format!("{stem}.tile{index:0digits$}"),
    };
    out.with_file_name(name)
}

/// `word` as one word of a POSIX shell command line.
pub fn shell_quote(word: &str) -> String {
    let plain = !word.is_empty()
        && word
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "_-+=./:,%@".contains(c));
    if plain {
        word.to_string()
    } else {
        format!("'{}'", word.replace('\'', r"'\''"))
    }
}

/// The render command lines of `count` tiles of the render `args` describe (`whitted render`'s
/// arguments, or course-style ones starting with an option), then the merge line. `exe` names
/// the program. The caller has checked that `args` parse as a render and that the image has
/// room for `count` tiles.
pub fn tile_lines(exe: &str, count: u32, args: &[String]) -> Result<Vec<String>> {
    // Where each output file name sits in `args`.
    let mut outputs: Vec<usize> = Vec::new();
    let mut i = 0;
    while i < args.len() {
        let skip = match option_name(&args[i]).as_deref() {
            Some("o" | "output" | "normals") => {
                outputs.push(i + 1);
                1
            }
            Some("depth") => {
                outputs.push(i + 3);
                3
            }
            Some(name @ ("crop" | "tile" | "ray_tree" | "ray_tree_image")) => {
                return Err(Error::Usage(format!(
                    "option --{} has no place in `whitted tiles`: it picks the tiles itself",
                    name.replace('_', "-")
                )));
            }
            _ => 0,
        };
        i += 1 + skip;
    }
    let outputs: Vec<usize> = outputs.into_iter().filter(|&k| k < args.len()).collect();
    if outputs.is_empty() {
        return Err(Error::Usage(
            "expected an output file: whitted tiles N SCENE -o OUT [OPTIONS]".to_string(),
        ));
    }
    let modern = args.first().is_some_and(|a| option_name(a).is_none());
    let prefix = if modern {
        format!("{} render", shell_quote(exe))
    } else {
        shell_quote(exe)
    };
    let mut lines = Vec::with_capacity(count as usize + 1);
    for tile in 0..count {
        let words: Vec<String> = args
            .iter()
            .enumerate()
            .map(|(k, a)| {
                if outputs.contains(&k) {
                    piece_path(Path::new(a), tile, count)
                        .to_string_lossy()
                        .into_owned()
                } else {
                    a.clone()
                }
            })
            .map(|w| shell_quote(&w))
            .collect();
        lines.push(format!(
            "{prefix} {} --tile {tile}/{count}",
            words.join(" ")
        ));
    }
    let merges: Vec<String> = outputs
        .iter()
        .map(|&k| {
            let out = Path::new(&args[k]);
            let pieces: Vec<String> = (0..count)
                .map(|t| shell_quote(&piece_path(out, t, count).to_string_lossy()))
                .collect();
            format!(
                "{} merge {} {}",
                shell_quote(exe),
                shell_quote(&args[k]),
                pieces.join(" ")
            )
        })
        .collect();
    lines.push(merges.join(" && "));
    Ok(lines)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pieces_are_numbered_with_as_many_digits_as_the_last() {
        assert_eq!(
            piece_path(Path::new("out/big.exr"), 3, 16),
            Path::new("out/big.tile03.exr")
        );
        assert_eq!(
            piece_path(Path::new("a.png"), 0, 1),
            Path::new("a.tile0.png")
        );
        assert_eq!(
            piece_path(Path::new("a.png"), 7, 10),
            Path::new("a.tile7.png")
        );
        assert_eq!(
            piece_path(Path::new("a.png"), 7, 101),
            Path::new("a.tile007.png")
        );
    }

    #[test]
    fn words_are_quoted_only_when_a_shell_would_split_or_expand_them() {
        assert_eq!(shell_quote("scenes/a.txt"), "scenes/a.txt");
        assert_eq!(shell_quote("my scene.txt"), "'my scene.txt'");
        assert_eq!(shell_quote("it's"), r"'it'\''s'");
        assert_eq!(shell_quote(""), "''");
        assert_eq!(shell_quote("-0.5"), "-0.5");
    }

    #[test]
    fn every_output_is_renamed_per_tile_and_merged_on_the_last_line() {
        let args: Vec<String> = "s.txt --size 64 48 -o c.png --depth 9 11 d.exr --normals n.pfm"
            .split(' ')
            .map(String::from)
            .collect();
        let lines = tile_lines("whitted", 2, &args).unwrap();
        assert_eq!(
            lines,
            [
                "whitted render s.txt --size 64 48 -o c.tile0.png --depth 9 11 d.tile0.exr \
                 --normals n.tile0.pfm --tile 0/2",
                "whitted render s.txt --size 64 48 -o c.tile1.png --depth 9 11 d.tile1.exr \
                 --normals n.tile1.pfm --tile 1/2",
                "whitted merge c.png c.tile0.png c.tile1.png && whitted merge d.exr \
                 d.tile0.exr d.tile1.exr && whitted merge n.pfm n.tile0.pfm n.tile1.pfm",
            ]
        );
        let course: Vec<String> = "-input s.txt -size 8 16 -output o.tga"
            .split(' ')
            .map(String::from)
            .collect();
        assert_eq!(
            tile_lines("./whitted", 2, &course).unwrap()[1],
            "./whitted -input s.txt -size 8 16 -output o.tile1.tga --tile 1/2"
        );
        let tiled: Vec<String> = ["s.txt", "-o", "a.png", "--tile", "0/2"]
            .map(String::from)
            .to_vec();
        assert!(tile_lines("whitted", 2, &tiled).is_err());
    }
}
