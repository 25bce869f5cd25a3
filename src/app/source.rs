//! What a checkpoint needs to rebuild a run (the application's part, saved opaque by the
//! driver's `run::checkpoint`): the built-in bar with its parameters, or a scene file's
//! text and the directory of its meshes; and the files such a run reads.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::error::Error;
use crate::run::checkpoint::InputFile;

/// What to rebuild on resume.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum RunSource {
    /// The impacting bar (`signorini bar`), with its parameters.
    Bar {
        /// The bar scene as run (boxed: a bar scene is several times a scene file's
        /// path and text).
        scene: Box<crate::scene::bar::BarScene>,
    },
    /// A scene file: its text as run (a later edit of the file does not change the
    /// resumed run) and the directory its relative mesh paths start from.
    Scene {
        /// The scene file's path (for messages).
        file: PathBuf,
        /// Its TOML text.
        toml: String,
        /// The directory of relative mesh paths.
        base_dir: PathBuf,
    },
}

impl RunSource {
    /// The form the driver's checkpoint keeps.
    pub fn to_value(&self) -> serde_json::Value {
        serde_json::to_value(self).expect("a run source serializes")
    }

    /// Reads back what [`RunSource::to_value`] gave, from the checkpoint `file`.
    pub fn from_checkpoint(value: &serde_json::Value, file: &Path) -> Result<RunSource, Error> {
        serde_json::from_value(value.clone()).map_err(|e| {
            Error::bad_file(
                file,
                "`source`",
                format!("not a run this build can rebuild ({e})"),
            )
        })
    }

    /// The files the run reads: the scene file and its mesh and field files (none for the
    /// bar).
    pub fn input_files(&self) -> Result<Vec<InputFile>, Error> {
        match self {
            RunSource::Bar { .. } => Ok(Vec::new()),
            RunSource::Scene {
                file,
                toml,
                base_dir,
            } => {
                let scene = crate::scene::file::Scene::from_toml(toml)?;
                let mut files = Vec::new();
                if !file.as_os_str().is_empty() {
                    files.push(InputFile::of(file)?);
                }
                for path in scene.data_files() {
                    files.push(InputFile::of(&base_dir.join(path))?);
                }
                Ok(files)
            }
        }
    }
}
