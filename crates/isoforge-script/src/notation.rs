//! Math notation on top of Rhai: `^` is power and binds as in mathematics.
//!
//! Rhai's `^` is exclusive-or with the lowest precedence (`x^2 + y^2` would parse as
//! `x ^ (2 + y) ^ 2`), and its unary minus binds tighter than any binary operator (`-x**2`
//! is `(-x)**2`). Models come from math, where `x^2 + y^2` is a sum of squares and
//! `exp(-x^2)` is a Gaussian. So before compiling, this pass rewrites the source: every
//! `^` becomes rhai's `**` (power, right-associative, above `*` and `/`), and a unary minus
//! in front of a power (`-x^2`) gets brackets (`-(x**2)`). Strings and comments are left
//! alone. The pass keeps a column map, so errors still point at the text the user wrote.

/// A token's kind, as far as this pass needs to know.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    Ident,
    Number,
    Str,
    Punct(char),
    /// `**`
    Pow,
    /// `^=`
    CaretAssign,
}

#[derive(Clone, Copy, Debug)]
struct Token {
    kind: Kind,
    /// Byte range in the source.
    start: usize,
    end: usize,
}

/// The rewritten source and the way back to the original columns.
pub struct Rewritten {
    /// The source to compile.
    pub source: String,
    /// For each line (0-based), the original 1-based column of each rewritten column.
    columns: Vec<Vec<usize>>,
}

impl Rewritten {
    /// The original column of a 1-based (line, column) of the rewritten source.
    pub fn original_column(&self, line: usize, column: usize) -> usize {
        line.checked_sub(1)
            .and_then(|l| self.columns.get(l))
            .and_then(|cols| column.checked_sub(1).and_then(|c| cols.get(c)))
            .copied()
            .unwrap_or(column)
    }
}

fn lex(src: &str) -> Vec<Token> {
    let bytes = src.as_bytes();
    let mut tokens = Vec::new();
    let mut i = 0;
    let at = |k: usize| bytes.get(k).copied().unwrap_or(0);
    while i < bytes.len() {
        let c = bytes[i];
        let start = i;
        let kind = if c.is_ascii_whitespace() {
            i += 1;
            continue;
        } else if c == b'/' && at(i + 1) == b'/' {
            while i < bytes.len() && bytes[i] != b'\n' {
                i += 1;
            }
            continue;
        } else if c == b'/' && at(i + 1) == b'*' {
            // Rhai's block comments nest.
            let mut depth = 0;
            while i < bytes.len() {
                if bytes[i] == b'/' && at(i + 1) == b'*' {
                    depth += 1;
                    i += 2;
                } else if bytes[i] == b'*' && at(i + 1) == b'/' {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    i += 1;
                }
            }
            continue;
        } else if c == b'"' || c == b'\'' || c == b'`' {
            i += 1;
            while i < bytes.len() && bytes[i] != c {
                i += if bytes[i] == b'\\' && c != b'`' { 2 } else { 1 };
            }
            i += 1;
            Kind::Str
        } else if c.is_ascii_digit() {
            let radix_prefix = c == b'0' && matches!(at(i + 1), b'x' | b'o' | b'b');
            i += 1;
            loop {
                let d = at(i);
                if d.is_ascii_alphanumeric() || d == b'_' {
                    let exponent = !radix_prefix && matches!(d, b'e' | b'E');
                    i += 1;
                    if exponent && matches!(at(i), b'+' | b'-') {
                        i += 1;
                    }
                } else if d == b'.' && at(i + 1).is_ascii_digit() {
                    i += 1;
                } else {
                    break;
                }
            }
            Kind::Number
        } else if c.is_ascii_alphabetic() || c == b'_' || c >= 0x80 {
            while i < bytes.len()
                && (bytes[i].is_ascii_alphanumeric() || bytes[i] == b'_' || bytes[i] >= 0x80)
            {
                i += 1;
            }
            Kind::Ident
        } else if c == b'*' && at(i + 1) == b'*' {
            i += 2;
            Kind::Pow
        } else if c == b'^' && at(i + 1) == b'=' {
            i += 2;
            Kind::CaretAssign
        } else {
            i += 1;
            Kind::Punct(c as char)
        };
        tokens.push(Token {
            kind,
            start,
            end: i.min(bytes.len()),
        });
    }
    tokens
}

/// Words after which a `-` starts an operand rather than subtracting.
const KEYWORDS: [&str; 9] = [
    "return", "throw", "in", "else", "do", "if", "while", "until", "switch",
];

fn is_unary_minus(src: &str, tokens: &[Token], i: usize) -> bool {
    if tokens[i].kind != Kind::Punct('-') {
        return false;
    }
    let Some(prev) = i.checked_sub(1).map(|p| tokens[p]) else {
        return true;
    };
    match prev.kind {
        Kind::Number | Kind::Str => false,
        Kind::Ident => KEYWORDS.contains(&&src[prev.start..prev.end]),
        Kind::Punct(p) => !matches!(p, ')' | ']' | '}'),
        // `2^-x` is 2^(-x) already: rhai parses the exponent's unary minus itself.
        Kind::Pow | Kind::CaretAssign => false,
    }
}

/// The index of the bracket closing the one at `open`, if any.
fn matching(tokens: &[Token], open: usize) -> Option<usize> {
    let (o, c) = match tokens[open].kind {
        Kind::Punct('(') => ('(', ')'),
        Kind::Punct('[') => ('[', ']'),
        _ => return None,
    };
    let mut depth = 0usize;
    for (k, t) in tokens.iter().enumerate().skip(open) {
        if t.kind == Kind::Punct(o) {
            depth += 1;
        } else if t.kind == Kind::Punct(c) {
            depth -= 1;
            if depth == 0 {
                return Some(k);
            }
        }
    }
    None
}

/// The last token of the operand starting at `k` (a name, number, call, bracketed group,
/// with indexing and `.method(..)` suffixes), if it is one this pass understands.
fn operand_end(tokens: &[Token], k: usize) -> Option<usize> {
    let mut end = match tokens.get(k)?.kind {
        Kind::Ident | Kind::Number | Kind::Str => k,
        Kind::Punct('(') | Kind::Punct('[') => matching(tokens, k)?,
        _ => return None,
    };
    loop {
        match tokens.get(end + 1).map(|t| t.kind) {
            Some(Kind::Punct('(')) | Some(Kind::Punct('[')) => end = matching(tokens, end + 1)?,
            Some(Kind::Punct('.')) if tokens.get(end + 2).map(|t| t.kind) == Some(Kind::Ident) => {
                end += 2
            }
            _ => return Some(end),
        }
    }
}

/// If a power chain (`a ^ b ^ c`, exponents possibly negated) starts at `k`, its last token.
fn power_chain_end(tokens: &[Token], k: usize) -> Option<usize> {
    let mut end = operand_end(tokens, k)?;
    let mut saw_power = false;
    while tokens
        .get(end + 1)
        .is_some_and(|t| matches!(t.kind, Kind::Punct('^') | Kind::Pow))
    {
        let mut next = end + 2;
        while tokens
            .get(next)
            .is_some_and(|t| matches!(t.kind, Kind::Punct('-') | Kind::Punct('+')))
        {
            next += 1;
        }
        end = operand_end(tokens, next)?;
        saw_power = true;
    }
    saw_power.then_some(end)
}

/// Rewrites `^` to `**` and brackets negated powers; see the module docs.
pub fn rewrite(src: &str) -> Rewritten {
    let tokens = lex(src);
    // (byte offset, text to insert, bytes replaced)
    let mut edits: Vec<(usize, &str, usize)> = Vec::new();
    for (i, t) in tokens.iter().enumerate() {
        match t.kind {
            Kind::Punct('^') => edits.push((t.start, "**", 1)),
            Kind::CaretAssign => edits.push((t.start, "**=", 2)),
            _ if is_unary_minus(src, &tokens, i) => {
                if let Some(end) = power_chain_end(&tokens, i + 1) {
                    edits.push((tokens[i + 1].start, "(", 0));
                    edits.push((tokens[end].end, ")", 0));
                }
            }
            _ => {}
        }
    }
    edits.sort_by_key(|e| e.0);
    apply(src, &edits)
}

fn apply(src: &str, edits: &[(usize, &str, usize)]) -> Rewritten {
    let mut out = String::with_capacity(src.len() + edits.len() * 2);
    let mut columns: Vec<Vec<usize>> = vec![Vec::new()];
    let mut col = 1; // original column of the next original character
    let mut pending = edits.iter().peekable();
    let mut skip = 0;
    for (offset, ch) in src.char_indices() {
        while let Some(&&(at, text, replaced)) = pending.peek() {
            if at != offset {
                break;
            }
            for c in text.chars() {
                out.push(c);
                if let Some(line) = columns.last_mut() {
                    line.push(col);
                }
            }
            skip += replaced;
            pending.next();
        }
        if skip > 0 {
            skip -= ch.len_utf8();
            col += 1;
            continue;
        }
        out.push(ch);
        if ch == '\n' {
            columns.push(Vec::new());
            col = 1;
        } else {
            if let Some(line) = columns.last_mut() {
                line.push(col);
            }
            col += 1;
        }
    }
    for &(_, text, _) in pending {
        out.push_str(text);
    }
    Rewritten {
        source: out,
        columns,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rw(s: &str) -> String {
        rewrite(s).source
    }

    #[test]
    fn caret_becomes_power() {
        assert_eq!(rw("x^2 + y^2"), "x**2 + y**2");
        assert_eq!(rw("a ^= 2"), "a **= 2");
        assert_eq!(rw("2^-1"), "2**-1");
    }

    #[test]
    fn negated_powers_get_brackets() {
        assert_eq!(rw("exp(-x^2-y^2)"), "exp(-(x**2)-y**2)");
        assert_eq!(rw("-2^2"), "-(2**2)");
        assert_eq!(rw("a / -b^2"), "a / -(b**2)");
        assert_eq!(rw("-f(x)[0].y^2^3"), "-(f(x)[0].y**2**3)");
        assert_eq!(rw("-(x+1)^-2 * 3"), "-((x+1)**-2) * 3");
        assert_eq!(rw("return -x^2;"), "return -(x**2);");
        assert_eq!(rw("|t| -t^2"), "|t| -(t**2)");
    }

    #[test]
    fn plain_minus_is_untouched() {
        assert_eq!(rw("a - b^2"), "a - b**2");
        assert_eq!(rw("-x + 1"), "-x + 1");
        assert_eq!(rw("f(a) - 2^x"), "f(a) - 2**x");
        assert_eq!(rw("1e-5 - x"), "1e-5 - x");
    }

    #[test]
    fn strings_and_comments_are_untouched() {
        assert_eq!(
            rw("\"a^b\" // x^2\n/* -y^2 /* ^ */ */ z^2"),
            "\"a^b\" // x^2\n/* -y^2 /* ^ */ */ z**2"
        );
        assert_eq!(rw("'^' + `x^${y}`"), "'^' + `x^${y}`");
    }

    #[test]
    fn columns_map_back() {
        let r = rewrite("let a = -x^2 + q;\nfoo");
        // "let a = -(x**2) + q;": `q` is at column 19 rewritten, 16 originally.
        assert_eq!(&r.source[..20], "let a = -(x**2) + q;");
        assert_eq!(r.original_column(1, 19), 16);
        assert_eq!(r.original_column(1, 9), 9);
        assert_eq!(r.original_column(2, 1), 1);
    }

    #[test]
    fn broken_input_does_not_panic() {
        for s in [
            "-(", "-x^", "^", "-[1, 2", "\"open", "/* open", "-x^(", "0x1e-", "é^2",
        ] {
            let _ = rewrite(s);
        }
    }
}
