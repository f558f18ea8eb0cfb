//! Error codes of the Arm API and the error type every method returns.

use std::fmt;

/// The Arm API's result codes, with the numeric values the vendor-neutral API defines.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum AbcErrorCode {
    /// 0: success.
    Success,
    /// -1: an error no other code describes.
    UnknownError,
    /// -2: a local wait timed out.
    Timeout,
    /// -3: the handle (connection) is not valid.
    InvalidHandle,
    /// -4: the call is not valid in the current state.
    InvalidState,
    /// -5: the arm is not connected yet.
    NotInitialized,
    /// -6: this vendor cannot do this.
    NotImplemented,
    /// -7: an argument is invalid (wrong length, unknown vendor, not finite).
    InvalidArgument,
    /// -50: a configuration parameter is missing or malformed.
    ParamError,
    /// -51: a parameter is outside its range.
    ParamOutOfRange,
    /// -100: the arm reports an error.
    ArmError,
    /// -101: the controller refused the command.
    ArmCtrlFalse,
    /// -102: sending to the arm failed.
    ArmDataSendFailed,
    /// -103: receiving from the arm failed (connection lost).
    ArmDataReceiveFailed,
    /// -104: the arm's reply could not be understood.
    ArmReturnDataErr,
    /// -105: a check on the arm's side failed.
    ArmCheckFailed,
    /// -106: the arm did not answer or arrive in time.
    ArmTimeout,
    /// -107: the target is outside what the arm can reach.
    ArmOutOfRange,
}

impl AbcErrorCode {
    /// Every code, in table order.
    pub const ALL: [Self; 18] = [
        Self::Success,
        Self::UnknownError,
        Self::Timeout,
        Self::InvalidHandle,
        Self::InvalidState,
        Self::NotInitialized,
        Self::NotImplemented,
        Self::InvalidArgument,
        Self::ParamError,
        Self::ParamOutOfRange,
        Self::ArmError,
        Self::ArmCtrlFalse,
        Self::ArmDataSendFailed,
        Self::ArmDataReceiveFailed,
        Self::ArmReturnDataErr,
        Self::ArmCheckFailed,
        Self::ArmTimeout,
        Self::ArmOutOfRange,
    ];

    /// The numeric value.
    pub fn value(self) -> i32 {
        match self {
            Self::Success => 0,
            Self::UnknownError => -1,
            Self::Timeout => -2,
            Self::InvalidHandle => -3,
            Self::InvalidState => -4,
            Self::NotInitialized => -5,
            Self::NotImplemented => -6,
            Self::InvalidArgument => -7,
            Self::ParamError => -50,
            Self::ParamOutOfRange => -51,
            Self::ArmError => -100,
            Self::ArmCtrlFalse => -101,
            Self::ArmDataSendFailed => -102,
            Self::ArmDataReceiveFailed => -103,
            Self::ArmReturnDataErr => -104,
            Self::ArmCheckFailed => -105,
            Self::ArmTimeout => -106,
            Self::ArmOutOfRange => -107,
        }
    }

    /// The code with numeric value `value`, if it is one.
    pub fn from_value(value: i32) -> Option<Self> {
        Self::ALL.into_iter().find(|c| c.value() == value)
    }

    /// The upper-case name (`ARM_OUT_OF_RANGE`).
    pub fn name(self) -> &'static str {
        match self {
            Self::Success => "SUCCESS",
            Self::UnknownError => "UNKNOWN_ERROR",
            Self::Timeout => "TIMEOUT",
            Self::InvalidHandle => "INVALID_HANDLE",
            Self::InvalidState => "INVALID_STATE",
            Self::NotInitialized => "NOT_INITIALIZED",
            Self::NotImplemented => "NOT_IMPLEMENTED",
            Self::InvalidArgument => "INVALID_ARGUMENT",
            Self::ParamError => "PARAM_ERROR",
            Self::ParamOutOfRange => "PARAM_OUT_OF_RANGE",
            Self::ArmError => "ARM_ERROR",
            Self::ArmCtrlFalse => "ARM_CTRL_FALSE",
            Self::ArmDataSendFailed => "ARM_DATA_SEND_FAILED",
            Self::ArmDataReceiveFailed => "ARM_DATA_RECEIVE_FAILED",
            Self::ArmReturnDataErr => "ARM_RETURN_DATA_ERR",
            Self::ArmCheckFailed => "ARM_CHECK_FAILED",
            Self::ArmTimeout => "ARM_TIMEOUT",
            Self::ArmOutOfRange => "ARM_OUT_OF_RANGE",
        }
    }
}

impl fmt::Display for AbcErrorCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} ({})", self.name(), self.value())
    }
}

type Source = Box<dyn std::error::Error + Send + Sync + 'static>;

/// A failed Arm API call: the code, a message saying what failed, and the underlying error.
#[derive(Debug, thiserror::Error)]
#[error("{code}: {message}")]
pub struct ArmError {
    /// The result code (never [`AbcErrorCode::Success`]).
    pub code: AbcErrorCode,
    /// What failed, in words.
    pub message: String,
    /// The driver or parser error behind it, if any.
    #[source]
    pub source: Option<Source>,
}

impl ArmError {
    /// An error with `code` and `message`.
    pub fn new(code: AbcErrorCode, message: impl Into<String>) -> Self {
        Self {
            code,
            message: message.into(),
            source: None,
        }
    }

    /// An error with `code` caused by `source` (its text becomes the message).
    pub fn caused_by(
        code: AbcErrorCode,
        source: impl std::error::Error + Send + Sync + 'static,
    ) -> Self {
        Self {
            code,
            message: source.to_string(),
            source: Some(Box::new(source)),
        }
    }

    /// `NOT_IMPLEMENTED` for `method` on `vendor`.
    pub fn not_implemented(vendor: &str, method: &str) -> Self {
        Self::new(
            AbcErrorCode::NotImplemented,
            format!("{method} is not available on {vendor} arms"),
        )
    }

    /// `NOT_INITIALIZED`: the arm is not connected.
    pub fn not_connected(name: &str) -> Self {
        Self::new(
            AbcErrorCode::NotInitialized,
            format!("arm {name:?} is not connected (call connect first)"),
        )
    }

    /// `PARAM_OUT_OF_RANGE` for `field` = `value` outside `range`.
    pub fn out_of_range(field: &str, value: impl fmt::Display, range: &str) -> Self {
        Self::new(
            AbcErrorCode::ParamOutOfRange,
            format!("{field} = {value} is outside {range}"),
        )
    }

    /// The numeric value of the code.
    pub fn value(&self) -> i32 {
        self.code.value()
    }
}

/// The result of an Arm API call.
pub type ArmResult<T> = Result<T, ArmError>;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_have_the_api_numbers() {
        let expected = [
            ("SUCCESS", 0),
            ("UNKNOWN_ERROR", -1),
            ("TIMEOUT", -2),
            ("INVALID_HANDLE", -3),
            ("INVALID_STATE", -4),
            ("NOT_INITIALIZED", -5),
            ("NOT_IMPLEMENTED", -6),
            ("INVALID_ARGUMENT", -7),
            ("PARAM_ERROR", -50),
            ("PARAM_OUT_OF_RANGE", -51),
            ("ARM_ERROR", -100),
            ("ARM_CTRL_FALSE", -101),
            ("ARM_DATA_SEND_FAILED", -102),
            ("ARM_DATA_RECEIVE_FAILED", -103),
            ("ARM_RETURN_DATA_ERR", -104),
            ("ARM_CHECK_FAILED", -105),
            ("ARM_TIMEOUT", -106),
            ("ARM_OUT_OF_RANGE", -107),
        ];
        let got: Vec<_> = AbcErrorCode::ALL
            .iter()
            .map(|c| (c.name(), c.value()))
            .collect();
        assert_eq!(got, expected);
    }

    #[test]
    fn values_map_back_to_their_code() {
        for code in AbcErrorCode::ALL {
            assert_eq!(AbcErrorCode::from_value(code.value()), Some(code));
        }
        assert_eq!(AbcErrorCode::from_value(-8), None);
        assert_eq!(AbcErrorCode::from_value(1), None);
    }

    #[test]
    fn the_error_text_names_code_value_and_cause() {
        let e = ArmError::out_of_range("v", 120, "1..=100");
        assert_eq!(e.value(), -51);
        assert_eq!(
            e.to_string(),
            "PARAM_OUT_OF_RANGE (-51): v = 120 is outside 1..=100"
        );
    }
}
