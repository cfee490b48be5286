//! One lock per run file: `RUN.mcap.lock` beside it, a path that no step
//! of a run renames (the run file itself is renamed over by a resume's
//! `.partial` and by `recover`), held exclusively (flock) by whatever
//! writes or rewrites `RUN.mcap`: a run, `--resume`, `--from … -o`, and
//! `recover`. The kernel releases it when the holder exits, however it
//! exits (kill -9 included). It records its holder (pid, host, start
//! time), so a refusal names who has the file.
//!
//! The lock file stays after the run: deleting it while another process
//! waits to open it would let two holders lock two different files.

use std::fs::File;
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// A held run-file lock; released when dropped.
#[derive(Debug)]
pub struct RunLock {
    _file: File,
    path: PathBuf,
}

/// Where the lock of run file `run` lives.
pub fn lock_path(run: &Path) -> PathBuf {
    let mut name = run.as_os_str().to_owned();
    name.push(".lock");
    PathBuf::from(name)
}

impl RunLock {
    /// Takes the lock of run file `run` for `what` (e.g. "run", "resume",
    /// "recover"), or says who holds it.
    pub fn acquire(run: &Path, what: &str) -> Result<RunLock, String> {
        let path = lock_path(run);
        let mut file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(&path)
            .map_err(|e| format!("cannot open the lock `{}`: {e}", path.display()))?;
        #[cfg(unix)]
        {
            use std::os::unix::io::AsRawFd;
            // SAFETY: flock on a descriptor this function owns.
            if unsafe { libc::flock(file.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) } != 0 {
                let mut holder = String::new();
                let _ = file.read_to_string(&mut holder);
                let holder = holder.trim();
                return Err(format!(
                    "another slipfront run is writing this file: `{}` is held by {} (its lock \
                     `{}`); wait for it to end or stop it",
                    run.display(),
                    if holder.is_empty() {
                        "a process that has not recorded itself yet"
                    } else {
                        holder
                    },
                    path.display()
                ));
            }
        }
        let holder = format!(
            "slipfront {what}, pid {} on {}, since unix time {}",
            std::process::id(),
            host_name(),
            crate::io::checkpoint::unix_now()
        );
        // Best effort: the lock holds whether or not its note is written.
        let _ = file
            .set_len(0)
            .and_then(|_| file.seek(SeekFrom::Start(0)))
            .and_then(|_| file.write_all(holder.as_bytes()))
            .and_then(|_| file.flush());
        Ok(RunLock { _file: file, path })
    }

    pub fn path(&self) -> &Path {
        &self.path
    }
}

fn host_name() -> String {
    #[cfg(unix)]
    {
        let mut buf = [0u8; 256];
        // SAFETY: gethostname writes at most buf.len() bytes into buf.
        if unsafe { libc::gethostname(buf.as_mut_ptr().cast(), buf.len()) } == 0 {
            let end = buf.iter().position(|&b| b == 0).unwrap_or(buf.len());
            return String::from_utf8_lossy(&buf[..end]).into_owned();
        }
    }
    "an unknown host".to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_holder_is_refused_with_the_first_named_and_the_lock_is_released_on_drop() {
        let dir = std::env::temp_dir().join(format!("slipfront-lock-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let run = dir.join("r.mcap");
        let first = RunLock::acquire(&run, "run").unwrap();
        assert_eq!(first.path(), dir.join("r.mcap.lock"));
        let refused = RunLock::acquire(&run, "resume").unwrap_err();
        assert!(
            refused.contains("another slipfront run is writing this file"),
            "{refused}"
        );
        assert!(
            refused.contains(&format!("slipfront run, pid {}", std::process::id())),
            "{refused}"
        );
        drop(first);
        let again = RunLock::acquire(&run, "recover").unwrap();
        drop(again);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
