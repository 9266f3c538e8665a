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

/// A path the settings carry must be UTF-8 text: screenshots and scene files hold them as
/// text (JSON and TOML strings), so another would make a render whose settings cannot be
/// written. Refused before anything is rendered, naming the path.
pub(crate) fn check_path(
    name: impl Into<std::borrow::Cow<'static, str>>,
    path: &std::path::Path,
) -> Result<(), SettingsError> {
    if path.to_str().is_some() {
        return Ok(());
    }
    Err(SettingsError {
        name: name.into(),
        value: format!("'{}'", path.display()),
        reason: "is not UTF-8 text, and raylab writes the paths of its settings as text \
                 (rename the file or its folder)",
    })
}
