//! One module per subcommand; each exposes clap `Args` and a `run` that builds its own runtime.

pub mod bus_args;
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
    let mut parts: Vec<String> = Vec::new();
    for cause in error.chain() {
        let part = cause.to_string();
        if parts.iter().any(|said| said.contains(&part)) {
            continue;
        }
        // A context such as "cannot read x.log" over a cause that already begins with it
        // ("cannot read x.log: No such file…"): say the fuller one, once.
        match parts.last_mut() {
            Some(last) if part.starts_with(last.as_str()) => *last = part,
            _ => parts.push(part),
        }
    }
    armhil::harness::elide_long_tokens(&parts.join(": "))
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
    fn a_context_the_cause_begins_with_is_said_once() {
        let io = std::io::Error::from_raw_os_error(2);
        let error = anyhow::Error::new(Echoing { source: io }).context("cannot read x.log");
        let text = error_text(&error);
        assert_eq!(text.matches("cannot read x.log").count(), 1, "{text}");
        assert!(text.starts_with("cannot read x.log: "), "{text}");
        assert!(text.contains("os error 2"), "{text}");
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
