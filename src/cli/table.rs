//! The machinery behind every subcommand's option table: an [`Opt`] says how an option is
//! spelled, which values it takes, where `--help` lists it and what it does; [`parse`] walks a
//! command line through a table and [`help`] prints the same table. Spellings are matched after
//! dropping one or two leading dashes and reading `-` inside names as `_`, so `-shade_back`,
//! `--shade-back` and `--shade_back` are one option. A leaf of `cli/`: `render.rs` and
//! `bench.rs` hold the tables, `mod.rs` dispatches to them.
//!
//! What every table gets for free: `-h`/`--help` (anywhere) asks for the help text; an unknown
//! option is refused with the nearest known spelling (edit distance); an option given twice
//! must repeat its values (flags may repeat freely); a missing value is named by its
//! description (`option --size: expected a height in pixels, found nothing`).

use std::path::PathBuf;
use std::str::FromStr;

use crate::error::{Error, Result};

/// One option of a command line: its spellings, its values, its `--help` entry, and its
/// handler, which reads the values in order from [`Values`] and stores them in `T`.
pub struct Opt<T: 'static> {
    /// The modern spelling (`--shade-back`), or "" for an option only the course's command
    /// lines use.
    pub long: &'static str,
    /// The course's spelling (`-shade_back`), or "" when the course has no such option.
    pub course: &'static str,
    /// A one-letter alias (`-o`), or "".
    pub short: &'static str,
    /// Each value the option takes, in order: its name in `--help` and its description in
    /// errors, `("NEAR", "a near distance")`. Empty for a flag.
    pub values: &'static [(&'static str, &'static str)],
    /// The `--help` section it is listed under (the section's title line).
    pub section: &'static str,
    /// Its `--help` text, one paragraph (wrapped when printed).
    pub help: &'static str,
    /// What it does with its values.
    pub apply: fn(&mut T, &mut Values) -> Result<()>,
}

impl<T> Opt<T> {
    /// The spelling shown in `--help` and in messages: the modern one, else the course's.
    pub fn name(&self) -> &'static str {
        if self.long.is_empty() {
            self.course
        } else {
            self.long
        }
    }

    /// The spelling for a command line of the given style.
    pub fn spelling(&self, course_style: bool) -> &'static str {
        if course_style && !self.course.is_empty() {
            self.course
        } else {
            self.name()
        }
    }

    /// Every non-empty spelling.
    pub fn spellings(&self) -> impl Iterator<Item = &'static str> {
        [self.short, self.long, self.course]
            .into_iter()
            .filter(|s| !s.is_empty())
    }

    /// Whether command-line word `name` (already through [`option_name`]) spells this option.
    fn is(&self, name: &str) -> bool {
        self.spellings()
            .any(|s| option_name(s) == Some(name.to_string()))
    }

    /// `-o, --output FILE`: the left column of `--help`.
    fn label(&self) -> String {
        let mut label = String::new();
        if !self.short.is_empty() {
            label.push_str(self.short);
            label.push_str(", ");
        }
        label.push_str(self.name());
        for (value, _) in self.values {
            label.push(' ');
            label.push_str(value);
        }
        label
    }
}

/// The option a command-line word names, normalised (`--shade-back` -> `shade_back`), or `None`
/// for a bare word (a positional argument; `-` alone is one).
pub fn option_name(word: &str) -> Option<String> {
    let name = word
        .strip_prefix("--")
        .or_else(|| word.strip_prefix('-').filter(|n| !n.is_empty()))?;
    Some(name.replace('-', "_"))
}

/// The values one occurrence of an option was given, read in order by its handler; each read
/// names the value's description when it is missing or malformed.
pub struct Values<'a> {
    option: &'a str,
    given: &'a [String],
    specs: &'static [(&'static str, &'static str)],
    next: usize,
}

impl<'a> Values<'a> {
    /// The option as it was typed.
    pub fn option(&self) -> &'a str {
        self.option
    }

    /// A usage error about this option: `option {typed}: {msg}`.
    pub fn error(&self, msg: impl std::fmt::Display) -> Error {
        Error::Usage(format!("option {}: {msg}", self.option))
    }

    /// The description of value `k`.
    fn what(&self, k: usize) -> &'static str {
        self.specs.get(k).map_or("a value", |(_, what)| what)
    }

    /// The next value as typed.
    pub fn text(&mut self) -> Result<&'a str> {
        let k = self.next;
        self.next += 1;
        self.given
            .get(k)
            .map(String::as_str)
            .ok_or_else(|| self.error(format_args!("expected {}, found nothing", self.what(k))))
    }

    /// The next value, picked by `pick` (`None`: not one it knows).
    pub fn choice<V>(&mut self, pick: impl FnOnce(&str) -> Option<V>) -> Result<V> {
        let v = self.text()?;
        pick(v).ok_or_else(|| self.malformed(v))
    }

    /// The next value as a number of type `N`.
    pub fn number<N: FromStr>(&mut self) -> Result<N> {
        self.choice(|v| v.parse().ok())
    }

    /// The next value as a finite number.
    pub fn finite(&mut self) -> Result<f32> {
        self.choice(|v| v.parse::<f32>().ok().filter(|x| x.is_finite()))
    }

    /// The next value as a file name (not empty).
    pub fn path(&mut self) -> Result<PathBuf> {
        let k = self.next;
        match self.text()? {
            "" => Err(self.error(format_args!("expected {}, found nothing", self.what(k)))),
            v => Ok(PathBuf::from(v)),
        }
    }

    /// The error for the value just read, `v`.
    fn malformed(&self, v: &str) -> Error {
        self.error(format_args!(
            "expected {}, found `{v}`",
            self.what(self.next - 1)
        ))
    }

    /// After the handler: every value the option takes must have been there.
    fn finish(&mut self) -> Result<()> {
        if self.given.len() < self.specs.len() {
            self.next = self.given.len();
            self.text()?;
        }
        Ok(())
    }
}

/// A command line's table and how it words what it refuses.
pub struct Table<T: 'static> {
    pub options: &'static [Opt<T>],
    /// The start of the unknown-option error: `unknown option`, `bench: unknown option`.
    pub unknown: &'static str,
}

impl<T> Table<T> {
    /// The option spelled `spelling` (any spelling of it).
    pub fn get(&self, spelling: &str) -> Option<&Opt<T>> {
        let name = option_name(spelling)?;
        self.options.iter().find(|o| o.is(&name))
    }

    /// The index of the option spelled `spelling`.
    pub fn index(&self, spelling: &str) -> Option<usize> {
        let name = option_name(spelling)?;
        self.options.iter().position(|o| o.is(&name))
    }

    /// The index of the option command-line word `word` (normalised: `name`) names, or the
    /// unknown-option error, with the nearest known spelling when one is close.
    fn find(&self, word: &str, name: &str) -> Result<usize> {
        if let Some(i) = self.options.iter().position(|o| o.is(name)) {
            return Ok(i);
        }
        let dashes = |s: &str| s.len() - s.trim_start_matches('-').len();
        let nearest = self
            .options
            .iter()
            .flat_map(Opt::spellings)
            .filter_map(|s| {
                let known = option_name(s)?;
                let d = edit_distance(name, &known);
                let close = name.chars().count() >= 2 && d <= (known.chars().count() / 3).max(1);
                close.then_some(((d, dashes(s) != dashes(word)), s))
            })
            .min_by_key(|(key, _)| *key);
        Err(Error::Usage(match nearest {
            Some((_, s)) => format!("{} `{word}`: did you mean {s}?", self.unknown),
            None => format!("{} `{word}`", self.unknown),
        }))
    }
}

/// What a command line asked for beyond its options.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Parsed {
    /// Run the command.
    Run,
    /// Print its help text instead.
    Help,
}

/// Walks `args` through `table`, calling each option's handler on `target`. A bare word is
/// the value of option `positional` (the first time only), or refused.
pub fn parse<T>(
    table: &Table<T>,
    args: &[String],
    target: &mut T,
    positional: Option<&str>,
) -> Result<Parsed> {
    let positional = positional.and_then(|p| table.index(p));
    let mut seen: Vec<Option<&[String]>> = vec![None; table.options.len()];
    let mut k = 0;
    while k < args.len() {
        let word = args[k].as_str();
        k += 1;
        let (index, given, typed) = match option_name(word) {
            Some(name) if name == "help" || name == "h" => return Ok(Parsed::Help),
            Some(name) => {
                let index = table.find(word, &name)?;
                let end = (k + table.options[index].values.len()).min(args.len());
                let given = &args[k..end];
                k = end;
                (index, given, word)
            }
            None => match positional {
                Some(index) if seen[index].is_none() => {
                    (index, &args[k - 1..k], table.options[index].name())
                }
                _ => return Err(Error::Usage(format!("unexpected argument `{word}`"))),
            },
        };
        let opt = &table.options[index];
        if let Some(before) = seen[index] {
            if given.len() == opt.values.len() && before != given {
                return Err(Error::Usage(format!(
                    "option {typed} given twice with different values: `{}`, then `{}`",
                    before.join(" "),
                    given.join(" ")
                )));
            }
        }
        seen[index] = Some(given);
        let mut values = Values {
            option: typed,
            given,
            specs: opt.values,
            next: 0,
        };
        (opt.apply)(target, &mut values)?;
        values.finish()?;
    }
    Ok(Parsed::Run)
}

/// The option sections of `table` for `--help`: each section's title, then one entry per
/// option, its label in a left column and its help text wrapped beside it.
pub fn help<T>(table: &Table<T>) -> String {
    const INDENT: usize = 4;
    const WIDTH: usize = 100;
    const MAX_LABEL: usize = 26;
    let column = INDENT
        + 2
        + table
            .options
            .iter()
            .map(|o| o.label().len())
            .filter(|&n| n <= MAX_LABEL)
            .max()
            .unwrap_or(0);
    let mut sections: Vec<&str> = Vec::new();
    for opt in table.options {
        if !sections.contains(&opt.section) {
            sections.push(opt.section);
        }
    }
    let mut out = String::new();
    for section in sections {
        out.push_str(section);
        out.push_str(":\n");
        for opt in table.options.iter().filter(|o| o.section == section) {
            let label = format!("{:INDENT$}{}", "", opt.label());
            let mut lines = wrap(opt.help, WIDTH - column).into_iter();
            let first = lines.next().unwrap_or_default();
            if label.len() + 2 <= column {
                out.push_str(format!("{label:column$}{first}").trim_end());
            } else {
                out.push_str(&label);
                out.push_str(&format!("\n{:column$}{first}", ""));
            }
            out.push('\n');
            for line in lines {
                out.push_str(&format!("{:column$}{line}\n", ""));
            }
        }
        out.push('\n');
    }
    out
}

/// `text` in lines of at most `width` characters (a longer word gets a line of its own).
pub fn wrap(text: &str, width: usize) -> Vec<String> {
    let mut lines = Vec::new();
    let mut line = String::new();
    for word in text.split_whitespace() {
        if !line.is_empty() && line.len() + 1 + word.len() > width {
            lines.push(std::mem::take(&mut line));
        }
        if !line.is_empty() {
            line.push(' ');
        }
        line.push_str(word);
    }
    lines.push(line);
    lines
}

/// The number of single-character edits (insert, delete, replace, swap two neighbours) that
/// turn `a` into `b` (optimal string alignment distance).
pub fn edit_distance(a: &str, b: &str) -> usize {
    let (a, b): (Vec<char>, Vec<char>) = (a.chars().collect(), b.chars().collect());
    let mut d = vec![vec![0usize; b.len() + 1]; a.len() + 1];
    for (i, row) in d.iter_mut().enumerate() {
        row[0] = i;
    }
    for (j, cell) in d[0].iter_mut().enumerate() {
        *cell = j;
    }
    for i in 1..=a.len() {
        for j in 1..=b.len() {
            let cost = usize::from(a[i - 1] != b[j - 1]);
            let mut best = (d[i - 1][j] + 1)
                .min(d[i][j - 1] + 1)
                .min(d[i - 1][j - 1] + cost);
            if i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] {
                best = best.min(d[i - 2][j - 2] + 1);
            }
            d[i][j] = best;
        }
    }
    d[a.len()][b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn edit_distances() {
        assert_eq!(edit_distance("shadow", "shadows"), 1);
        assert_eq!(edit_distance("wieght", "weight"), 1);
        assert_eq!(edit_distance("", "abc"), 3);
        assert_eq!(edit_distance("kitten", "sitting"), 3);
        assert_eq!(edit_distance("same", "same"), 0);
    }

    #[test]
    fn option_names_drop_dashes_and_read_hyphens_as_underscores() {
        assert_eq!(option_name("--shade-back").as_deref(), Some("shade_back"));
        assert_eq!(option_name("-shade_back").as_deref(), Some("shade_back"));
        assert_eq!(option_name("-o").as_deref(), Some("o"));
        assert_eq!(option_name("-"), None);
        assert_eq!(option_name("scene.txt"), None);
    }
}
