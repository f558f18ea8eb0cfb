//! Classifying what arrives on the TCP connection: replies (tagged by `command` or `state`),
//! arrival events and other unsolicited notices.

use serde_json::{Map, Value};

use super::request::Tag;
use super::types::{Arrival, Device};
use super::DecodeError;

/// The tag of a received reply.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum ReplyTag {
    /// Tagged `"command":"…"`.
    Command(String),
    /// Tagged `"state":"…"`.
    State(String),
}

impl ReplyTag {
    /// True when this is the reply tag a request expects.
    pub fn is(&self, tag: Tag) -> bool {
        match (self, tag) {
            (Self::Command(a), Tag::Command(b)) | (Self::State(a), Tag::State(b)) => a == b,
            _ => false,
        }
    }
}

/// Unsolicited `state` tags that are never a reply to a request.
const NOTICES: [&str; 5] = [
    "program_run_finish",
    "hand_follow_angle",
    "hand_follow_pos",
    "save_trajectory_finish",
    "conduct_project",
];

/// One decoded TCP message.
#[derive(Debug, Clone, PartialEq)]
pub enum Message {
    /// A reply to some request.
    Reply {
        /// Its tag.
        tag: ReplyTag,
        /// The whole object.
        body: Map<String, Value>,
    },
    /// `current_trajectory_state`.
    Arrival(Arrival),
    /// Another unsolicited notice (`program_run_finish`, …).
    Notice {
        /// The `state` tag.
        tag: String,
        /// The whole object.
        body: Map<String, Value>,
    },
}

/// Parses one object cut by the splitter.
pub fn decode_message(text: &str) -> Result<Message, DecodeError> {
    let value: Value = serde_json::from_str(text).map_err(|e| DecodeError::Json(e.to_string()))?;
    let Value::Object(body) = value else {
        return Err(DecodeError::NotAnObject);
    };
    // `command` wins: some replies carry both, with `state` as the result flag
    // (`{"command":"set_gripper","state":true}`).
    if let Some(Value::String(c)) = body.get("command") {
        return Ok(Message::Reply {
            tag: ReplyTag::Command(c.clone()),
            body,
        });
    }
    let Some(Value::String(state)) = body.get("state") else {
        return Err(DecodeError::NoTag);
    };
    if state == "current_trajectory_state" {
        return decode_arrival(&body).map(Message::Arrival);
    }
    if NOTICES.contains(&state.as_str()) {
        return Ok(Message::Notice {
            tag: state.clone(),
            body,
        });
    }
    Ok(Message::Reply {
        tag: ReplyTag::State(state.clone()),
        body,
    })
}

fn decode_arrival(body: &Map<String, Value>) -> Result<Arrival, DecodeError> {
    let ok = body
        .get("trajectory_state")
        .and_then(Value::as_bool)
        .ok_or(DecodeError::Field("trajectory_state"))?;
    let device = body
        .get("device")
        .and_then(Value::as_i64)
        .ok_or(DecodeError::Field("device"))?;
    // Older gripper/hand events omit trajectory_connect; that means "nothing more follows".
    let more = match body.get("trajectory_connect") {
        None => false,
        Some(v) => v.as_i64().ok_or(DecodeError::Field("trajectory_connect"))? != 0,
    };
    Ok(Arrival {
        ok,
        device: Device::from_wire(device),
        more_follow: more,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn classifies() {
        let m = decode_message(r#"{"command":"set_gripper","state":true}"#).unwrap();
        assert!(
            matches!(m, Message::Reply { tag: ReplyTag::Command(c), .. } if c == "set_gripper")
        );
        let m = decode_message(
            r#"{"state":"current_trajectory_state","trajectory_state":false,"device":1}"#,
        )
        .unwrap();
        assert_eq!(
            m,
            Message::Arrival(Arrival {
                ok: false,
                device: Device::Gripper,
                more_follow: false
            })
        );
        let m = decode_message(r#"{"state":"program_run_finish","finish_id":3}"#).unwrap();
        assert!(matches!(m, Message::Notice { .. }));
        assert_eq!(decode_message("[1]"), Err(DecodeError::NotAnObject));
        assert_eq!(decode_message(r#"{"x":1}"#), Err(DecodeError::NoTag));
        assert!(matches!(decode_message("{oops"), Err(DecodeError::Json(_))));
    }
}
