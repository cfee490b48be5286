//! A test's scratch folder in the system's temporary folder: empty when
//! made, removed when the test ends, and kept when the test fails (its
//! path on stderr), so that a failure can be looked at. The test files
//! each made their own and left them behind: about 270 MB a test run, most
//! of it `hardening.rs`'s damaged run files.

use std::ffi::OsStr;
use std::path::{Path, PathBuf};

pub struct Scratch(PathBuf);

impl Scratch {
    /// An empty folder `slipfront-{kind}-{process}-{name}`: `name` is one
    /// test's (tests of one file run at once, in one process).
    pub fn new(kind: &str, name: &str) -> Scratch {
        let dir =
            std::env::temp_dir().join(format!("slipfront-{kind}-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        Scratch(dir)
    }
}

impl std::ops::Deref for Scratch {
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

impl AsRef<OsStr> for Scratch {
    fn as_ref(&self) -> &OsStr {
        self.0.as_os_str()
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        if std::thread::panicking() {
            eprintln!("kept for the failure: {}", self.0.display());
        } else {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}
