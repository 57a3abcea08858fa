//! The scene-file tokenizer: text to a list of tokens, each with the line and column it starts
//! at, so that every later error can say `path:line:col`. It is the first step after file input
//! (`input.rs`) and feeds the cursor (`cursor.rs`) that the grammar (`parse.rs`) reads through.
//!
//! ```text
//! &str --tokenize--> [Token { text, line, col }] --> Cursor --> parse.rs grammar
//! ```
//!
//! Scene-file syntax at this level: tokens are separated by whitespace; `{` and `}` are tokens
//! of their own and need no spaces around them (`Group{numObjects 1` is four tokens); `#` at the
//! start of a token begins a comment that runs to the end of the line (inside a token, as in
//! `a#b`, it is an ordinary character). Lines and columns count from 1; a column counts
//! characters, not bytes.

/// One token of scene text and where it starts.
#[derive(Clone, Copy, Debug)]
pub(super) struct Token<'a> {
    pub(super) text: &'a str,
    pub(super) line: usize,
    pub(super) col: usize,
}

/// Splits `text` into tokens; also returns the position just past the end. `None` when the
/// token list does not fit in memory (a huge file fails cleanly instead of aborting).
pub(super) fn tokenize<'a>(text: &'a str) -> Option<(Vec<Token<'a>>, (usize, usize))> {
    fn push<'a>(tokens: &mut Vec<Token<'a>>, token: Token<'a>) -> Option<()> {
        if tokens.len() == tokens.capacity() {
            tokens.try_reserve(tokens.len().max(256)).ok()?;
        }
        tokens.push(token);
        Some(())
    }
    let mut tokens = Vec::new();
    let (mut line, mut col) = (1, 1);
    let mut start: Option<(usize, usize, usize)> = None; // byte offset, line, col
    let mut in_comment = false;
    let flush = |tokens: &mut Vec<Token<'a>>,
                 start: &mut Option<(usize, usize, usize)>,
                 end: usize|
     -> Option<()> {
        match start.take() {
            Some((s, line, col)) => push(
                tokens,
                Token {
                    text: &text[s..end],
                    line,
                    col,
                },
            ),
            None => Some(()),
        }
    };
    for (i, ch) in text.char_indices() {
        if in_comment {
            if ch == '\n' {
                in_comment = false;
            }
        } else if ch.is_whitespace() {
            flush(&mut tokens, &mut start, i)?;
        } else if ch == '{' || ch == '}' {
            flush(&mut tokens, &mut start, i)?;
            let text = &text[i..i + 1];
            push(&mut tokens, Token { text, line, col })?;
        } else if ch == '#' && start.is_none() {
            in_comment = true;
        } else if start.is_none() {
            start = Some((i, line, col));
        }
        if ch == '\n' {
            line += 1;
            col = 1;
        } else {
            col += 1;
        }
    }
    flush(&mut tokens, &mut start, text.len())?;
    Some((tokens, (line, col)))
}

/// How a token is shown in "found ..." messages: quoted, escaped, and cut short if long.
pub(super) fn describe(tok: Option<&Token<'_>>) -> String {
    match tok {
        None => "end of file".to_string(),
        Some(t) => {
            let mut s: String = t
                .text
                .chars()
                .take(24)
                .flat_map(char::escape_default)
                .collect();
            if t.text.chars().count() > 24 {
                s.push_str("...");
            }
            format!("`{s}`")
        }
    }
}
