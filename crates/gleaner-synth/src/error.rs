use thiserror::Error;

/// Invalid synthetic-farm configuration. Each message names the setting and carries the
/// offending value.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum SynthError {
    /// A numeric setting outside its allowed range (or not finite).
    #[error("invalid setting {name} = {value}: {reason}")]
    InvalidSetting {
        /// The [`crate::SynthConfig`] field, e.g. `sensor_count`.
        name: &'static str,
        /// The offending value, as text.
        value: String,
        /// What the setting must satisfy.
        reason: &'static str,
    },
    /// A depth list that is unusable (duplicate or zero depths).
    #[error(
        "invalid depth list {name} = {depths:?}: depths must be distinct whole centimetres in 1..=1000"
    )]
    InvalidDepths {
        /// `vw_depths_cm` or `t_depths_cm`.
        name: &'static str,
        /// The offending list, cm.
        depths: Vec<u32>,
    },
    /// A position or modality rejected by `gleaner-field`.
    #[error(transparent)]
    Field(#[from] gleaner_field::FieldError),
}
