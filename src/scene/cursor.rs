//! The cursor the scene grammar reads tokens through: a position in the token list of
//! `token.rs`, the "expect this, else a positioned error" steps (a keyword, a number, a vector,
//! a colour, a count, a block of named fields) and the wording of every "expected ..., found
//! ..." message. The grammar (`blocks.rs`, `parse.rs`) and the checks over the parsed tree
//! (`passes.rs`) build all their errors here, so messages share one form:
//! `path:line:col: expected ..., found ...`.
//!
//! ```text
//! [Token] --> Cursor { peek, keyword, number, vec3, color, count, block_fields } --> grammar
//! ```
//!
//! Scene-file syntax of values: a number is a decimal floating-point literal as Rust's `f32`
//! reads it (`1`, `-0.5`, `.5`, `2.`, `1e-3`, `+4`) and must be finite; a count (`numObjects`,
//! `MaterialIndex`, `octaves`, ...) is a whole number from 0 to 4294967295 with no sign but an
//! optional `+`; a vector is three numbers; a colour is three numbers none of them negative; a
//! direction (normals, axes, camera directions) is a vector that is not zero. Keywords are
//! case-sensitive. A block of fields, `Name { field value ... }`, takes its fields in any order,
//! each at most once.

use std::path::Path;

use super::token::{Token, describe};
use crate::error::{Error, Result};
use crate::math::Vec3;

/// A read position in a scene's tokens, and the file they came from (for messages).
pub(super) struct Cursor<'a> {
    path: &'a Path,
    tokens: Vec<Token<'a>>,
    pos: usize,
    /// The position just past the last character, where "found end of file" points.
    eof: (usize, usize),
}

impl<'a> Cursor<'a> {
    pub(super) fn new(tokens: Vec<Token<'a>>, eof: (usize, usize), path: &'a Path) -> Cursor<'a> {
        Cursor {
            path,
            tokens,
            pos: 0,
            eof,
        }
    }

    /// The file the tokens came from.
    pub(super) fn path(&self) -> &'a Path {
        self.path
    }

    /// The token at the cursor, if any.
    pub(super) fn peek(&self) -> Option<Token<'a>> {
        self.tokens.get(self.pos).copied()
    }

    /// Steps past the token at the cursor (after a `peek` that matched).
    pub(super) fn advance(&mut self) {
        self.pos += 1;
    }

    /// Steps back onto the token just read (to report an error at it).
    pub(super) fn back(&mut self) {
        self.pos -= 1;
    }

    /// The token just before the cursor (the closing brace of a block just read).
    pub(super) fn previous(&self) -> Token<'a> {
        self.tokens[self.pos.saturating_sub(1)]
    }

    /// A positioned error at `tok` (at the end of the file when `None`).
    pub(super) fn error_at(&self, tok: Option<&Token<'_>>, msg: String) -> Error {
        let (line, col) = tok.map_or(self.eof, |t| (t.line, t.col));
        Error::parse(self.path, line, col, msg)
    }

    pub(super) fn out_of_memory(&self) -> Error {
        Error::Limit(format!(
            "{}: cannot parse: the scene does not fit in memory",
            self.path.display()
        ))
    }

    /// "expected {what}, found {the token at the cursor}".
    pub(super) fn expected(&self, what: &str) -> Error {
        let tok = self.peek();
        self.error_at(
            tok.as_ref(),
            format!("expected {what}, found {}", describe(tok.as_ref())),
        )
    }

    /// A count promised more items than the block holds: "expected 3 objects (numObjects 3),
    /// found `}` after 2".
    pub(super) fn too_few(&self, noun: &str, field: &str, n: usize, got: usize) -> Error {
        let tok = self.peek();
        self.error_at(
            tok.as_ref(),
            format!(
                "expected {} ({field} {n}), found {} after {got}",
                plural(n, noun),
                describe(tok.as_ref())
            ),
        )
    }

    /// A block holds more items than its count: "expected `}` after 1 object (numObjects 1),
    /// found `Sphere`".
    pub(super) fn too_many(&self, noun: &str, field: &str, n: usize) -> Error {
        self.expected(&format!("`}}` after {} ({field} {n})", plural(n, noun)))
    }

    /// Any token; `what` names it if the file ends instead.
    pub(super) fn next(&mut self, what: &str) -> Result<Token<'a>> {
        match self.peek() {
            Some(t) => {
                self.pos += 1;
                Ok(t)
            }
            None => Err(self.expected(what)),
        }
    }

    /// Exactly the token `word`.
    pub(super) fn keyword(&mut self, word: &str) -> Result<Token<'a>> {
        match self.peek() {
            Some(t) if t.text == word => {
                self.pos += 1;
                Ok(t)
            }
            _ => Err(self.expected(&format!("`{word}`"))),
        }
    }

    /// A finite number; `what` names the field in messages.
    pub(super) fn number(&mut self, what: &str) -> Result<f32> {
        let tok = self.peek();
        match tok.map(|t| t.text.parse::<f32>()) {
            Some(Ok(v)) if v.is_finite() => {
                self.pos += 1;
                Ok(v)
            }
            Some(Ok(_)) => Err(self.error_at(
                tok.as_ref(),
                format!(
                    "expected a finite number for {what}, found {}",
                    describe(tok.as_ref())
                ),
            )),
            _ => Err(self.expected(&format!("a number for {what}"))),
        }
    }

    /// Three numbers.
    pub(super) fn vec3(&mut self, what: &str) -> Result<Vec3> {
        Ok(Vec3::new(
            self.number(what)?,
            self.number(what)?,
            self.number(what)?,
        ))
    }

    /// A vector that must not be zero (directions, normals, axes).
    pub(super) fn direction(&mut self, what: &str) -> Result<Vec3> {
        let at = self.peek();
        let v = self.vec3(what)?;
        if v.try_normalize().is_some() {
            Ok(v)
        } else {
            let kind = if v.length().is_finite() {
                "non-zero"
            } else {
                "finite-length"
            };
            Err(self.error_at(
                at.as_ref(),
                format!("expected a {kind} vector for {what}, found {}", vec_text(v)),
            ))
        }
    }

    /// A colour: three non-negative numbers (a negative channel is meaningless, and would let
    /// an overflow to infinity turn into NaN).
    pub(super) fn color(&mut self, what: &str) -> Result<Vec3> {
        let at = self.peek();
        let c = self.vec3(what)?;
        if c.min_element() >= 0.0 {
            Ok(c)
        } else {
            Err(self.error_at(
                at.as_ref(),
                format!(
                    "expected a colour with no negative channel for {what}, found {}",
                    vec_text(c)
                ),
            ))
        }
    }

    /// A number above zero.
    pub(super) fn positive(&mut self, what: &str) -> Result<f32> {
        let at = self.peek();
        let v = self.number(what)?;
        if v > 0.0 {
            Ok(v)
        } else {
            Err(self.error_at(
                at.as_ref(),
                format!(
                    "expected a positive number for {what}, found {}",
                    num_text(v)
                ),
            ))
        }
    }

    /// A whole number that fits a `u32`.
    pub(super) fn count(&mut self, what: &str) -> Result<usize> {
        let tok = self.peek();
        match tok.map(|t| t.text.parse::<u32>()) {
            Some(Ok(n)) => {
                self.pos += 1;
                Ok(n as usize)
            }
            Some(Err(e)) if *e.kind() == std::num::IntErrorKind::PosOverflow => Err(self.expected(
                &format!("a whole number for {what} of at most {}", u32::MAX),
            )),
            _ => Err(self.expected(&format!("a whole number for {what}"))),
        }
    }

    /// Reads `{ field value ... }` with fields in any order, each at most once; `read` parses the
    /// value of one field. Returns the names seen and the closing brace.
    pub(super) fn block_fields(
        &mut self,
        block: &str,
        names: &[&'static str],
        read: &mut dyn FnMut(&mut Self, &str) -> Result<()>,
    ) -> Result<(Vec<&'static str>, Token<'a>)> {
        self.keyword("{")?;
        let mut seen: Vec<&'static str> = Vec::new();
        loop {
            let Some(tok) = self.peek() else {
                return Err(self.expected(&format!("`}}` closing {block}")));
            };
            if tok.text == "}" {
                self.pos += 1;
                return Ok((seen, tok));
            }
            match names.iter().find(|n| **n == tok.text) {
                Some(name) => {
                    if seen.contains(name) {
                        return Err(self.error_at(
                            Some(&tok),
                            format!("expected `{name}` once in {block}, found it twice"),
                        ));
                    }
                    seen.push(name);
                    self.pos += 1;
                    read(self, name)?;
                }
                None => {
                    let list: Vec<String> = names.iter().map(|n| format!("`{n}`")).collect();
                    return Err(self.expected(&format!("{} or `}}` in {block}", list.join(", "))));
                }
            }
        }
    }

    /// The error for a required field `name` missing from a block read by `block_fields`
    /// (pointing at its closing brace `close`), or `Ok` if it was there.
    pub(super) fn require(
        &self,
        block: &str,
        seen: &[&str],
        close: &Token<'_>,
        name: &str,
    ) -> Result<()> {
        if seen.contains(&name) {
            Ok(())
        } else {
            Err(self.error_at(
                Some(close),
                format!("expected `{name}` in {block}, found `}}`"),
            ))
        }
    }
}

/// "1 object", "2 objects".
fn plural(n: usize, noun: &str) -> String {
    if n == 1 {
        format!("1 {noun}")
    } else {
        format!("{n} {noun}s")
    }
}

/// A number as messages show it: plain, or in exponent form when very large or small.
pub(super) fn num_text(x: f32) -> String {
    if x != 0.0 && x.is_finite() && !(1e-4..1e7).contains(&x.abs()) {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

/// A vector as messages show it: `(x y z)`.
pub(super) fn vec_text(v: Vec3) -> String {
    format!("({} {} {})", num_text(v.x), num_text(v.y), num_text(v.z))
}

/// Makes room for one more item; `Err` when memory runs out.
pub(super) fn grow<T>(items: &mut Vec<T>) -> std::result::Result<(), ()> {
    if items.len() == items.capacity() {
        items.try_reserve(items.len().max(4)).map_err(|_| ())?;
    }
    Ok(())
}
