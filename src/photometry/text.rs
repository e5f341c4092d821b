//! What both parsers share: one-line errors that name the file and line, numbers read
//! strictly (finite, integral where a count is meant), and the file's text.

use crate::{Error, Result};
use std::path::Path;

/// Largest angle count accepted on either axis: well beyond any real file (1° steps are
/// 361 × 361), small enough that a corrupt count cannot allocate gigabytes.
pub const MAX_ANGLES: usize = 100_000;
/// Largest candela table (angles × angles) accepted.
pub const MAX_VALUES: usize = 4_000_000;

/// `origin: line N` as the error's origin: `examp1.ies: line 14: ...`.
pub fn at(origin: &str, line: usize, message: impl Into<String>) -> Error {
    Error::input(format!("{origin}: line {line}"), message)
}

/// A file's bytes as text: a UTF-8 byte-order mark dropped, other encodings (Latin-1
/// manufacturer names) read lossily; numbers are ASCII either way.
pub fn read(path: &Path) -> Result<String> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let text = String::from_utf8_lossy(&bytes).into_owned();
    Ok(text
        .strip_prefix('\u{feff}')
        .map(str::to_string)
        .unwrap_or(text))
}

/// The lines of a text, without their CR.
pub fn lines(text: &str) -> Vec<&str> {
    text.split('\n')
        .map(|l| l.strip_suffix('\r').unwrap_or(l))
        .collect()
}

/// The 1-based number of the last line with anything on it (1 if none): where a file
/// that ends too early ends.
pub fn last_content(lines: &[&str]) -> usize {
    lines
        .iter()
        .rposition(|l| !l.trim().is_empty())
        .map_or(1, |k| k + 1)
}

/// A finite number, or why not.
pub fn number(token: &str) -> std::result::Result<f64, String> {
    if token.is_empty() {
        return Err("an empty line is not a number".into());
    }
    match token.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(format!("`{token}` is not a finite number")),
        Err(_) => Err(format!("`{token}` is not a number")),
    }
}

/// An integer in [lo, hi], written as an integer or (LM-63-1986 allows it) as `3.0`.
pub fn integer(token: &str, lo: i64, hi: i64) -> std::result::Result<i64, String> {
    let v = number(token)?;
    if v.fract() != 0.0 {
        return Err(format!("`{token}` is not a whole number"));
    }
    if v < lo as f64 || v > hi as f64 {
        return Err(format!("{token} is outside {lo}..={hi}"));
    }
    Ok(v as i64)
}

/// The numbers of a file after its text header: separated by blanks or commas, each with
/// its line number (1-based).
pub struct Tokens<'a> {
    origin: &'a str,
    items: Vec<(&'a str, usize)>,
    next: usize,
    /// The last line of the file, for "the file ends before ...".
    last_line: usize,
}

impl<'a> Tokens<'a> {
    /// The tokens of `lines`, the first of which is line `first_line`.
    pub fn new(origin: &'a str, lines: &[&'a str], first_line: usize) -> Tokens<'a> {
        let mut items = Vec::new();
        for (k, line) in lines.iter().enumerate() {
            for tok in line.split(|c: char| c.is_whitespace() || c == ',') {
                // DOS end-of-file marks are not data.
                let tok = tok.trim_matches('\u{1a}');
                if !tok.is_empty() {
                    items.push((tok, first_line + k));
                }
            }
        }
        let last_line = first_line + last_content(lines).saturating_sub(1);
        Tokens {
            origin,
            items,
            next: 0,
            last_line,
        }
    }

    pub fn origin(&self) -> &'a str {
        self.origin
    }

    /// The next token and its line, or the error "the file ends before `what`".
    pub fn token(&mut self, what: &str) -> Result<(&'a str, usize)> {
        match self.items.get(self.next) {
            Some(&t) => {
                self.next += 1;
                Ok(t)
            }
            None => Err(at(
                self.origin,
                self.last_line,
                format!("the file ends before {what}"),
            )),
        }
    }

    /// The next number and its line.
    pub fn number(&mut self, what: &str) -> Result<(f64, usize)> {
        let (tok, line) = self.token(what)?;
        number(tok)
            .map(|v| (v, line))
            .map_err(|m| at(self.origin, line, format!("{what}: {m}")))
    }

    /// The next integer in [lo, hi] and its line.
    pub fn integer(&mut self, what: &str, lo: i64, hi: i64) -> Result<(i64, usize)> {
        let (tok, line) = self.token(what)?;
        integer(tok, lo, hi)
            .map(|v| (v, line))
            .map_err(|m| at(self.origin, line, format!("{what}: {m}")))
    }

    /// `n` numbers and their lines; `what` names the list (`vertical angle`, ...).
    pub fn numbers(&mut self, n: usize, what: &str) -> Result<(Vec<f64>, Vec<usize>)> {
        let mut values = Vec::new();
        let mut lines = Vec::new();
        for k in 0..n {
            let (v, l) = self.number(&format!("{what} {} of {n}", k + 1))?;
            values.push(v);
            lines.push(l);
        }
        Ok((values, lines))
    }

    /// Errors if anything is left: the counts and the data disagree.
    pub fn finish(&self, counted: &str) -> Result<()> {
        match self.items.get(self.next) {
            None => Ok(()),
            Some(&(tok, line)) => Err(at(
                self.origin,
                line,
                format!("`{tok}` after the last value {counted}: the counts do not match the data"),
            )),
        }
    }
}

/// Errors unless `angles` increase strictly; `lines` are their lines.
pub fn check_increasing(origin: &str, angles: &[f64], lines: &[usize], what: &str) -> Result<()> {
    for k in 1..angles.len() {
        if angles[k] <= angles[k - 1] {
            return Err(at(
                origin,
                lines[k],
                format!(
                    "{what} {} ({}) does not increase from {} ({})",
                    k + 1,
                    angles[k],
                    k,
                    angles[k - 1]
                ),
            ));
        }
    }
    Ok(())
}

/// Errors unless every angle lies in [lo, hi].
pub fn check_range(
    origin: &str,
    angles: &[f64],
    lines: &[usize],
    what: &str,
    lo: f64,
    hi: f64,
) -> Result<()> {
    for (k, &a) in angles.iter().enumerate() {
        if !(lo..=hi).contains(&a) {
            return Err(at(
                origin,
                lines[k],
                format!("{what} {} is {a}°, outside {lo}..{hi}°", k + 1),
            ));
        }
    }
    Ok(())
}
