//! Error codes of the Arm API and the error type every method returns.

use std::fmt;

/// The Arm API's result codes, with the numeric values the vendor-neutral API defines.
///
/// The upper-case names (`ARM_OUT_OF_RANGE`) are the variants' names in screaming snake case.
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Hash,
    strum::IntoStaticStr,
    strum::VariantArray,
    strum::EnumCount,
)]
#[strum(serialize_all = "SCREAMING_SNAKE_CASE")]
#[repr(i32)]
pub enum AbcErrorCode {
    /// 0: success.
    Success = 0,
    /// -1: an error no other code describes.
    UnknownError = -1,
    /// -2: a local wait timed out.
    Timeout = -2,
    /// -3: the handle (connection) is not valid.
    InvalidHandle = -3,
    /// -4: the call is not valid in the current state.
    InvalidState = -4,
    /// -5: the arm is not connected yet.
    NotInitialized = -5,
    /// -6: this vendor cannot do this.
    NotImplemented = -6,
    /// -7: an argument is invalid (wrong length, unknown vendor, not finite).
    InvalidArgument = -7,
    /// -50: a configuration parameter is missing or malformed.
    ParamError = -50,
    /// -51: a parameter is outside its range.
    ParamOutOfRange = -51,
    /// -100: the arm reports an error.
    ArmError = -100,
    /// -101: the controller refused the command.
    ArmCtrlFalse = -101,
    /// -102: sending to the arm failed.
    ArmDataSendFailed = -102,
    /// -103: receiving from the arm failed (connection lost).
    ArmDataReceiveFailed = -103,
    /// -104: the arm's reply could not be understood.
    ArmReturnDataErr = -104,
    /// -105: a check on the arm's side failed.
    ArmCheckFailed = -105,
    /// -106: the arm did not answer or arrive in time.
    ArmTimeout = -106,
    /// -107: the target is outside what the arm can reach.
    ArmOutOfRange = -107,
}

impl AbcErrorCode {
    /// Every code, in table order.
    ///
    /// An array, built from the derived variant list, so callers iterate it by value.
    pub const ALL: [Self; <AbcErrorCode as strum::EnumCount>::COUNT] = {
        let variants = <AbcErrorCode as strum::VariantArray>::VARIANTS;
        let mut all = [AbcErrorCode::Success; <AbcErrorCode as strum::EnumCount>::COUNT];
        let mut i = 0;
        while i < all.len() {
            all[i] = variants[i];
            i += 1;
        }
        all
    };

    /// The numeric value.
    pub fn value(self) -> i32 {
        self as i32
    }

    /// The code with numeric value `value`, if it is one.
    pub fn from_value(value: i32) -> Option<Self> {
        Self::ALL.into_iter().find(|c| c.value() == value)
    }

    /// The upper-case name (`ARM_OUT_OF_RANGE`).
    pub fn name(self) -> &'static str {
        self.into()
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
