//! The YAML reader's errors in the words of someone writing the file: "unknown key `x`; did
//! you mean `y`?" rather than "unknown field", "expected a number" rather than "invalid f64".
//! Every YAML file the project reads (scenarios, robot files, rig files) says it this way,
//! and shows the line and long values of an error the same way.

/// Longest source line shown under an error, in bytes.
const MAX_SOURCE_LINE: usize = 240;
/// Longest run of non-blank characters an error message shows whole; longer ones (a 10 MB bad
/// token) are cut to their first [`ELIDED_KEEP`] characters and "…".
const LONGEST_TOKEN: usize = 80;
/// How many characters of an over-long token an error message keeps.
const ELIDED_KEEP: usize = 40;

/// `text` with every token (run of non-blank characters) longer than 80 characters cut to its
/// first 40 and "…", so a huge bad value is not echoed whole.
pub fn elide_long_tokens(text: &str) -> String {
    let mut out = String::with_capacity(text.len().min(4096));
    let mut token = String::new();
    let flush = |token: &mut String, out: &mut String| {
        if token.chars().count() > LONGEST_TOKEN {
            out.extend(token.chars().take(ELIDED_KEEP));
            out.push('…');
        } else {
            out.push_str(token);
        }
        token.clear();
    };
    for c in text.chars() {
        if c.is_whitespace() {
            flush(&mut token, &mut out);
            out.push(c);
        } else {
            token.push(c);
        }
    }
    flush(&mut token, &mut out);
    out
}

/// Line `line` (1-based) of `text`, to show under an error at it; `None` for line 0 (unknown)
/// and for a line too long to read on a terminal (the headline already says where).
pub fn source_line(text: &str, line: u64) -> Option<String> {
    let index = usize::try_from(line.checked_sub(1)?).unwrap_or(usize::MAX);
    text.lines()
        .nth(index)
        .filter(|shown| shown.len() <= MAX_SOURCE_LINE)
        .map(str::to_owned)
}

/// The reader's error as a message, without the position and the source snippet its own
/// rendering carries (callers print the position and the line themselves).
pub fn message(error: &serde_saphyr::Error) -> String {
    let raw = error.without_snippet().to_string();
    // The plain rendering ends with " at line L, column C".
    let message = match raw.rfind(" at line ") {
        Some(cut) => &raw[..cut],
        None => raw.as_str(),
    };
    suggest(&friendlier(message))
}

/// `; did you mean `x`?` when one of `candidates` is within two edits of `word`, else empty.
pub fn suggestion(word: &str, candidates: &[&str]) -> String {
    candidates
        .iter()
        .map(|c| (strsim::levenshtein(word, c), *c))
        .filter(|(d, c)| *d <= 2 && *d < c.len())
        .min()
        .map_or_else(String::new, |(_, c)| format!("; did you mean `{c}`?"))
}

/// Append "did you mean `x`?" to an unknown-key message when one expected key is close.
fn suggest(message: &str) -> String {
    let Some(rest) = message.strip_prefix("unknown key `") else {
        return message.to_owned();
    };
    let Some((key, tail)) = rest.split_once('`') else {
        return message.to_owned();
    };
    let Some(list) = tail.strip_prefix(", expected one of ") else {
        return message.to_owned();
    };
    let best = list
        .split(", ")
        .map(|c| (strsim::levenshtein(key, c), c))
        .filter(|(d, c)| *d <= 2 && *d < c.len())
        .min();
    match best {
        Some((_, candidate)) => format!("{message}; did you mean `{candidate}`?"),
        None => message.to_owned(),
    }
}

/// serde's type errors name Rust types; say what the file's author should write instead.
fn friendlier(message: &str) -> String {
    let replacements: [(&str, &str); 12] = [
        ("invalid u64", "expected a whole number >= 0"),
        ("invalid u32", "expected a whole number >= 0"),
        ("invalid u16", "expected a whole number >= 0"),
        ("invalid u8", "expected a whole number >= 0"),
        ("invalid i64", "expected a whole number"),
        ("invalid i32", "expected a whole number"),
        ("invalid floating point", "expected a number"),
        ("invalid f64", "expected a number"),
        ("invalid bool", "expected true or false"),
        ("expected sequence start", "expected a list ([a, b, ...])"),
        ("expected mapping start", "expected a mapping (key: value)"),
        ("unknown field", "unknown key"),
    ];
    for (from, to) in replacements {
        if let Some(rest) = message.strip_prefix(from) {
            return format!("{to}{rest}");
        }
    }
    if let Some(breach) = message.strip_prefix("budget breached: ") {
        return budget_words(breach);
    }
    message.to_owned()
}

/// The YAML parser's resource-limit error, which it renders as Rust debug text
/// (`Aliases { aliases: 50001 }`), in plain words.
fn budget_words(breach: &str) -> String {
    let name = breach.split([' ', '{']).next().unwrap_or(breach);
    let mut words = String::new();
    for c in name.chars() {
        if c.is_uppercase() && !words.is_empty() {
            words.push(' ');
        }
        words.extend(c.to_lowercase());
    }
    let count = breach
        .split(|c: char| !c.is_ascii_digit())
        .find(|part| !part.is_empty());
    let reached = count.map_or_else(String::new, |n| format!(" (reached {n})"));
    format!("the file exceeds the YAML reader's limit on {words}{reached}")
}
