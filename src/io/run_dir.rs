//! The run directory: which files a run owns, the checks on an output path before
//! anything is written, the lock that keeps two runs out of one directory, and the
//! atomic write (`NAME.part`, flushed, renamed into place).

use super::*;

/// Writes `bytes` to `path` atomically (write `path.part`, flush, sync, rename).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), Error> {
    let tmp = part_path(path);
    let mut f = File::create(&tmp).map_err(|e| Error::write(&tmp, e))?;
    f.write_all(bytes).map_err(|e| Error::write(&tmp, e))?;
    f.sync_all().map_err(|e| Error::write(&tmp, e))?;
    std::fs::rename(&tmp, path).map_err(|e| Error::write(path, e))
}

/// The files a run writes into its directory (besides `fields/frame_*.vtu`).
pub const RUN_FILES: [&str; 12] = [
    "summary.json",
    "history.csv",
    "fields.pvd",
    "fields.vtkhdf",
    "obstacles.vtu",
    "checkpoint.json",
    "contact_force.png",
    "contact_force.svg",
    "energy.png",
    "energy.svg",
    "violation.png",
    "violation.svg",
];

/// What a path is, for the messages of [`check_output_file`] and [`check_output_dir`].
pub(super) fn kind_of(md: &std::fs::Metadata) -> &'static str {
    let ft = md.file_type();
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt as _;
        if ft.is_block_device() || ft.is_char_device() {
            return "a device";
        }
        if ft.is_fifo() {
            return "a FIFO";
        }
        if ft.is_socket() {
            return "a socket";
        }
    }
    if ft.is_symlink() {
        "a symbolic link"
    } else if ft.is_dir() {
        "a directory"
    } else if ft.is_file() {
        "a regular file"
    } else {
        "not a regular file"
    }
}

/// Refuses (exit code 2) an output file `path` that exists as anything but a regular
/// file — a device, a FIFO, a socket, a directory, a symbolic link — or that is one of
/// the run's `inputs`: the atomic write renames over its target, which would replace a
/// device node (as root, `--solution /dev/full` did) or an input.
pub fn check_output_file(flag: &str, path: &Path, inputs: &[&Path]) -> Result<(), Error> {
    if let Ok(md) = std::fs::symlink_metadata(path) {
        if !md.file_type().is_file() {
            return Err(Error::invalid(
                flag,
                path.display(),
                &format!(
                    "is {}: an output is written as a regular file, never through a link \
                     or onto a device",
                    kind_of(&md)
                ),
            ));
        }
        let same = |a: &Path| matches!((std::fs::canonicalize(a), std::fs::canonicalize(path)), (Ok(x), Ok(y)) if x == y);
        if let Some(input) = inputs.iter().find(|i| same(i)) {
            return Err(Error::invalid(
                flag,
                path.display(),
                &format!(
                    "is the input {}: the output would replace it",
                    input.display()
                ),
            ));
        }
    }
    Ok(())
}

/// Refuses (exit code 2) an output directory that exists as anything but a directory.
pub fn check_output_dir(flag: &str, dir: &Path) -> Result<(), Error> {
    match std::fs::metadata(dir) {
        Ok(md) if !md.is_dir() => Err(Error::invalid(
            flag,
            dir.display(),
            &format!(
                "is {}, not a directory: choose a directory for the run",
                kind_of(&md)
            ),
        )),
        _ => Ok(()),
    }
}

/// The lock file a run holds in its output directory.
pub const LOCK_FILE: &str = ".signorini.lock";

/// How long [`RunLock::acquire`] waits for a lock that this process itself holds (a
/// child process between its fork and its exec) before refusing the directory.
pub(super) const SELF_HELD_RETRY: std::time::Duration = std::time::Duration::from_secs(2);

/// One run's hold on its output directory: the operating system's advisory exclusive
/// lock (`flock` on Unix, `LockFileEx` on Windows, through `std::fs::File::try_lock`) on
/// [`LOCK_FILE`], held for the run or its resume and released when dropped, or by the
/// kernel when the process dies (a killed run leaves no stale lock). The holder's
/// process id is written into the file so that a refused run can name it.
#[derive(Debug)]
pub struct RunLock {
    pub(super) _file: File,
}

impl RunLock {
    /// Creates `dir` if needed and takes its lock; a directory held by another run is
    /// refused (exit code 2) with the holder's process id.
    pub fn acquire(dir: &Path) -> Result<RunLock, Error> {
        check_output_dir("--out", dir)?;
        std::fs::create_dir_all(dir).map_err(|e| Error::write(dir, e))?;
        let path = dir.join(LOCK_FILE);
        let mut file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(&path)
            .map_err(|e| Error::write(&path, e))?;
        // a descriptor this process's threads let a child inherit between its fork and
        // its exec holds the lock for that moment (flock belongs to the open file,
        // which the child shares): when the holder is this process, try again for a
        // while before refusing
        let deadline = std::time::Instant::now() + SELF_HELD_RETRY;
        loop {
            match file.try_lock() {
                Ok(()) => break,
                Err(std::fs::TryLockError::WouldBlock) => {
                    let holder = std::fs::read_to_string(&path).unwrap_or_default();
                    let holder = holder.trim();
                    let ours = holder == std::process::id().to_string();
                    if ours && std::time::Instant::now() < deadline {
                        std::thread::sleep(std::time::Duration::from_millis(10));
                        continue;
                    }
                    let who = if ours {
                        format!("another run in this process (process {holder})")
                    } else if holder.is_empty() {
                        "another signorini run".to_string()
                    } else {
                        format!("another signorini run (process {holder})")
                    };
                    return Err(Error::invalid(
                        "--out",
                        dir.display(),
                        &format!(
                            "{who} is writing into this directory; wait for it to finish or \
                             choose another output directory"
                        ),
                    ));
                }
                Err(std::fs::TryLockError::Error(e)) => return Err(Error::write(&path, e)),
            }
        }
        file.set_len(0).map_err(|e| Error::write(&path, e))?;
        writeln!(file, "{}", std::process::id()).map_err(|e| Error::write(&path, e))?;
        file.flush().map_err(|e| Error::write(&path, e))?;
        Ok(RunLock { _file: file })
    }
}

/// Makes `dir` ready for a new run: creates it, and removes what an earlier run left
/// there that this run would write or that would contradict it (its summary, history,
/// frames, plots, checkpoint, and their leftover `.part` files: the names of
/// [`RUN_FILES`] and the frames, nothing else — a user's own files, `.part` or not, stay),
/// so a finished directory never mixes two runs.
pub fn prepare_run_dir(dir: &Path) -> Result<(), Error> {
    std::fs::create_dir_all(dir).map_err(|e| Error::write(dir, e))?;
    let entries = std::fs::read_dir(dir).map_err(|e| Error::write(dir, e))?;
    for e in entries {
        let path = e.map_err(|e| Error::write(dir, e))?.path();
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
        let ours = RUN_FILES.contains(&name)
            || name
                .strip_suffix(".part")
                .is_some_and(|stem| RUN_FILES.contains(&stem));
        if ours && path.is_file() {
            std::fs::remove_file(&path).map_err(|e| Error::write(&path, e))?;
        }
    }
    let frames = dir.join("fields");
    if frames.is_dir() {
        frames::remove_stale_frames(&frames)?;
    }
    Ok(())
}

/// The name a file has while it is written: `path` with `.part` appended.
pub fn part_path(path: &Path) -> PathBuf {
    let mut s = path.as_os_str().to_owned();
    s.push(".part");
    PathBuf::from(s)
}

/// Publishes the rows written so far of a file still being written as `path.part`: a
/// copy of the part, renamed onto `path` (so a reader sees the old copy or the new one,
/// never half of one). The part goes on growing, and the run's end renames it onto
/// `path` as usual. A run asked to stop mid-way (the Python package's interrupted
/// `run()`, which may go on later) leaves its history readable this way.
pub fn publish_part(path: &Path) -> Result<(), Error> {
    let part = part_path(path);
    let mut snapshot = path.as_os_str().to_owned();
    snapshot.push(".snapshot");
    let snapshot = PathBuf::from(snapshot);
    std::fs::copy(&part, &snapshot).map_err(|e| Error::write(&snapshot, e))?;
    std::fs::rename(&snapshot, path).map_err(|e| Error::write(path, e))
}
