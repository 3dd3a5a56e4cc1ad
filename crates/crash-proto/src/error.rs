//! Conversion errors: a message that cannot be turned into domain data.

use crash_core::CoreError;
use thiserror::Error;

#[derive(Debug, Error, Clone, PartialEq)]
pub enum ProtoError {
    #[error("protocol: message field '{0}' is missing")]
    Missing(&'static str),
    #[error("protocol: body {body}: '{field}' has {got} values, expected {expected}")]
    Length {
        body: u32,
        field: &'static str,
        got: usize,
        expected: usize,
    },
    #[error("protocol: {0}")]
    Invalid(String),
    #[error("protocol: a received body is invalid: {0}")]
    Core(#[from] CoreError),
}
