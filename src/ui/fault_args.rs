//! The web view's front end of the emulators' fault builders: a page command's JSON
//! arguments as `sim::fault_args` reads them.

use serde_json::{Map, Value};
use sim::fault_args::{FaultArgValue, FaultArgs};

/// A page command's arguments as a fault builder reads them: numbers, and words; a number
/// typed into a text box (`"1.5"`) is a number, an empty box or `null` is not given.
pub fn page_fault_args(args: &Map<String, Value>) -> FaultArgs {
    let mut out = FaultArgs::new();
    for (name, value) in args {
        let value = match value {
            Value::Null => continue,
            Value::Number(n) => match n.as_f64() {
                Some(x) => FaultArgValue::Number(x),
                None => FaultArgValue::Text(n.to_string()),
            },
            Value::String(s) if s.trim().is_empty() => continue,
            Value::String(s) => s
                .trim()
                .parse()
                .map_or_else(|_| FaultArgValue::Text(s.clone()), FaultArgValue::Number),
            other => FaultArgValue::Text(other.to_string()),
        };
        out.push(name.as_str(), value);
    }
    out
}

#[cfg(test)]
mod tests {
    use serde_json::json;

    use super::*;

    #[test]
    fn typed_numbers_count_and_empty_boxes_do_not() {
        let Value::Object(args) =
            json!({"joint": "2", "celsius": 95.5, "board": "main", "torque_nm": "", "x": null})
        else {
            unreachable!()
        };
        let read = page_fault_args(&args);
        assert_eq!(read.get("joint"), Some(&FaultArgValue::Number(2.0)));
        assert_eq!(read.get("celsius"), Some(&FaultArgValue::Number(95.5)));
        assert_eq!(read.get("board"), Some(&FaultArgValue::Text("main".into())));
        assert_eq!(read.get("torque_nm"), None);
        assert_eq!(read.get("x"), None);
    }
}
