//! The one error every `validate` returns, from a scene's parts up to the whole settings: which
//! value, what it was, and why raylab refuses it.

/// A value the renderer can't use; the message names it.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("invalid {name} {value}: {reason}")]
pub struct SettingsError {
    /// The value's name (`light power`), or for a scene's part its path in a scene file
    /// (`scene.models[0].height`).
    pub name: std::borrow::Cow<'static, str>,
    pub value: String,
    pub reason: &'static str,
}
