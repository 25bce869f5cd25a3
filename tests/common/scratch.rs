//! Scratch directories of the tests, removed when the test that made them passes (kept
//! after a failure, to look at). Used by the checkpoint and bad-input tests, which left
//! about 0.5 GB per run of the suite in the temporary directory; a run now leaves a few
//! small directories of other tests (3.8 MB).

use std::ops::Deref;
use std::path::{Path, PathBuf};

/// A directory under the temporary directory, emptied at creation and removed on drop
/// unless the thread is panicking.
pub struct Scratch(PathBuf);

impl Scratch {
    /// `signorini-{kind}-{pid}-{name}`, removed first if a previous run left it.
    pub fn new(kind: &str, name: &str) -> Self {
        let d =
            std::env::temp_dir().join(format!("signorini-{kind}-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        Scratch(d)
    }
}

impl Deref for Scratch {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<Path> for Scratch {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<std::ffi::OsStr> for Scratch {
    fn as_ref(&self) -> &std::ffi::OsStr {
        self.0.as_os_str()
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        if !std::thread::panicking() {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}
