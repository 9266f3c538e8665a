//! What is read from and written to disk: scene files ([`scene_file`], TOML) and
//! settings, alone or inside a screenshot ([`settings_file`]).

pub mod scene_file;
pub mod settings_file;
