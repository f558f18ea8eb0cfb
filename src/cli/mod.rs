//! One module per subcommand; each exposes clap `Args` and a `run` that builds its own runtime.

pub mod check;
pub mod decode;
pub mod logging;
pub mod record;
pub mod replay;
pub mod run;
pub mod signals;
pub mod sim;

/// An error and its causes as one line for the terminal: "outer: cause: cause", each cause
/// said once (many errors already print their source in their own text, so anyhow's `{:#}`
/// would repeat it), with over-long tokens elided.
pub fn error_text(error: &anyhow::Error) -> String {
    let mut text = String::new();
    for cause in error.chain() {
        let part = cause.to_string();
        if text.contains(&part) {
            continue;
        }
        if !text.is_empty() {
            text.push_str(": ");
        }
        text.push_str(&part);
    }
    armhil::harness::elide_long_tokens(&text)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, thiserror::Error)]
    #[error("cannot read x.log: {source}")]
    struct Echoing {
        source: std::io::Error,
    }

    #[test]
    fn a_cause_already_in_the_message_is_said_once() {
        let io = std::io::Error::from_raw_os_error(2);
        let error = anyhow::Error::new(Echoing { source: io }).context("replay failed");
        let text = error_text(&error);
        assert_eq!(text.matches("os error 2").count(), 1, "{text}");
        assert!(
            text.starts_with("replay failed: cannot read x.log: "),
            "{text}"
        );
    }

    #[test]
    fn distinct_causes_are_all_kept() {
        let error = anyhow::anyhow!("inner").context("outer");
        assert_eq!(error_text(&error), "outer: inner");
    }

    #[test]
    fn long_tokens_are_elided() {
        let token = "x".repeat(10_000_000);
        let error = anyhow::anyhow!("bad token {token} here");
        let text = error_text(&error);
        assert_eq!(text, format!("bad token {}… here", "x".repeat(40)));
        let short = "y".repeat(80);
        assert_eq!(error_text(&anyhow::anyhow!("{short}")), short);
    }
}
