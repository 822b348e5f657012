//! A private temporary directory: created atomically with mode 0700 under a random name, never
//! an existing path (a directory or link another user made in /tmp is not reused), removed
//! with its contents when dropped. `pdw-sweep explore` with no file computes its default basin
//! into one and removes it on exit, Ctrl-C included.

use std::os::unix::fs::{DirBuilderExt, PermissionsExt};
use std::path::{Path, PathBuf};

/// Names tried before giving up (each a fresh random name: a collision means someone else
/// holds it).
const ATTEMPTS: usize = 16;

/// A directory removed when dropped.
#[derive(Debug)]
pub struct PrivateDir(PathBuf);

impl PrivateDir {
    /// A new directory `<prefix><16 random hex digits>` in the system's temporary directory.
    pub fn new(prefix: &str) -> Result<PrivateDir, String> {
        let parent = std::env::temp_dir();
        let mut last = String::new();
        for _ in 0..ATTEMPTS {
            let name = format!(
                "{prefix}{}",
                crate::guard::hex(&crate::guard::random_bytes(8)?)
            );
            match PrivateDir::create(&parent.join(name)) {
                Ok(d) => return Ok(d),
                Err(e) => last = e,
            }
        }
        Err(last)
    }

    /// The directory `path`, created now with mode 0700; refused when anything exists there
    /// (a directory, a file or a link, dangling or not).
    pub fn create(path: &Path) -> Result<PrivateDir, String> {
        std::fs::DirBuilder::new()
            .mode(0o700)
            .create(path)
            .map_err(|e| {
                format!(
                    "cannot create the private directory '{}': {e} (an existing path is never reused)",
                    path.display()
                )
            })?;
        // the umask can only take bits away; set 0700 exactly
        std::fs::set_permissions(path, std::fs::Permissions::from_mode(0o700))
            .map_err(|e| format!("'{}': {e}", path.display()))?;
        Ok(PrivateDir(path.to_path_buf()))
    }

    pub fn path(&self) -> &Path {
        &self.0
    }
}

impl Drop for PrivateDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}
