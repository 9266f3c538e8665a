//! An output never replaces a file the command reads.

use super::options::RenderOptions;
use raylab_core::RenderSettings;

/// The files a command given `options` reads, beside the image it checks: the file given to
/// `--settings` or `--scene-file`, and every file its scene reads.
pub(super) fn files_read(
    options: &RenderOptions,
    settings: &RenderSettings,
) -> Vec<raylab_core::base::inputs::Input> {
    let given = [
        (&options.settings, "the --settings file"),
        (&options.scene_file, "the --scene-file file"),
    ];
    let mut files: Vec<_> = given
        .into_iter()
        .filter_map(|(path, what)| {
            let path = path.as_deref()?;
            Some(raylab_core::base::inputs::Input::new(path, what))
        })
        .collect();
    files.extend(settings.scene.files_read());
    files
}

/// Refuses an output (`option`'s `path`) that would replace one of the `files` `reader` reads
/// ([`raylab_core::base::inputs::refuse_output_onto`]), before any work. `--save-scene` needs no
/// such check: it never replaces a file ([`save_scene_file`]).
pub(super) fn refuse_output_onto(
    option: &str,
    path: &std::path::Path,
    reader: &str,
    files: Vec<raylab_core::base::inputs::Input>,
) -> anyhow::Result<()> {
    raylab_core::base::inputs::refuse_output_onto(option, path, reader, &files)
        .map_err(anyhow::Error::msg)
}
