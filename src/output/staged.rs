//! All or nothing: files written into a hidden folder inside the output folder, then moved into
//! place together, or everything put back as it was ([`Staged`], and the render's own files
//! through the same steps); and the checks of an output place made before any work.

use std::fs::{self, File};
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use super::names::TEMP_PREFIX;
use super::{io_err, Fault, OutputError, Step};
use crate::fsutil::kind_of;

/// Move the staged `names` from `temp` into `dir` and remove `stale` from it, all or nothing;
/// `temp` is removed unless putting things back failed (then it keeps the previous files).
pub(super) fn finish(
    dir: &Path,
    temp: PathBuf,
    names: &[String],
    stale: &[String],
    fault: &mut Fault<'_>,
) -> Result<Vec<PathBuf>, OutputError> {
    match install(dir, &temp, names, stale, fault) {
        Ok(paths) => {
            let _ = fs::remove_dir_all(&temp);
            // Make the renames durable where the platform can (best effort: not on Windows).
            if let Ok(d) = File::open(dir) {
                let _ = d.sync_all();
            }
            Ok(paths)
        }
        Err(InstallError::RolledBack(e)) => {
            let _ = fs::remove_dir_all(&temp);
            Err(e)
        }
        Err(InstallError::Stuck(cause, rollback)) => Err(OutputError::RollbackFailed {
            dir: dir.to_path_buf(),
            temp,
            cause: Box::new(cause),
            rollback,
        }),
    }
}

/// Any set of files written into one folder all or nothing, by the same rules as
/// [`write_render`](super::write_render): each file is written (and flushed) into a hidden folder inside `dir` as it
/// is [`add`](Staged::add)ed, so a long job holds only one file in memory at a time; nothing in
/// `dir` changes until [`commit`](Staged::commit), which moves them all into place (and removes
/// the files named [`stale`](Staged::remove_on_commit)), or puts everything back as it was. A
/// `Staged` dropped without a commit leaves `dir` untouched.
pub struct Staged {
    dir: PathBuf,
    temp: Option<PathBuf>,
    names: Vec<String>,
    stale: Vec<String>,
    /// The folders `new` made: taken away again if nothing is committed.
    created: NewDirs,
}

impl Staged {
    /// Start writing into `dir` (checked first, as [`check_out_dir`] does; created with its
    /// parents if missing, and removed again if nothing is committed).
    pub fn new(dir: &Path) -> Result<Staged, OutputError> {
        check_out_dir(dir, &[])?;
        let created = NewDirs::create(dir).map_err(io_err(dir, "create the directory"))?;
        let temp = match create_temp_dir(dir) {
            Ok(t) => t,
            Err(e) => {
                created.remove_if_empty();
                return Err(e);
            }
        };
        Ok(Staged {
            dir: dir.to_path_buf(),
            temp: Some(temp),
            names: Vec::new(),
            stale: Vec::new(),
            created,
        })
    }

    /// Stage file `name` (a plain file name, no folders) with `bytes`.
    pub fn add(&mut self, name: &str, bytes: &[u8]) -> Result<(), OutputError> {
        self.write_with(name, |out, target| {
            out.write_all(bytes).map_err(io_err(target, "write"))
        })
    }

    /// Stage file `name` (a plain file name, no folders) as `write` streams it into a buffered
    /// file (told where the file will go, for its errors): a large file is encoded straight to
    /// disk, never held whole.
    pub fn write_with(
        &mut self,
        name: &str,
        write: impl FnOnce(&mut io::BufWriter<File>, &Path) -> Result<(), OutputError>,
    ) -> Result<(), OutputError> {
        let (file, target) = self.create(name)?;
        let mut out = io::BufWriter::with_capacity(1 << 20, file);
        write(&mut out, &target)?;
        let file = out
            .into_inner()
            .map_err(|e| io_err(&target, "write")(e.into_error()))?;
        file.sync_all().map_err(io_err(&target, "write"))?;
        self.names.push(name.to_string());
        Ok(())
    }

    /// Stage file `name` to be written over a long job (an animation's APNG, frame by frame):
    /// the file in the hidden folder, and where it will go. The caller writes it whole and
    /// syncs it before [`commit`](Staged::commit), which moves it into place with the others.
    pub fn open(&mut self, name: &str) -> Result<(File, PathBuf), OutputError> {
        let opened = self.create(name)?;
        self.names.push(name.to_string());
        Ok(opened)
    }

    /// A new file `name` in the hidden folder (not yet staged), and where it will go.
    fn create(&self, name: &str) -> Result<(File, PathBuf), OutputError> {
        let target = self.dir.join(name);
        let plain = Path::new(name).file_name().is_some_and(|n| n == name);
        if !plain || name.starts_with(TEMP_PREFIX) || self.names.iter().any(|n| n == name) {
            return Err(io_err(&target, "write")(io::Error::new(
                io::ErrorKind::InvalidInput,
                "expected a new plain file name",
            )));
        }
        if fs::symlink_metadata(&target).is_ok_and(|m| m.is_dir()) {
            return Err(OutputError::TargetIsDirectory { path: target });
        }
        let Some(temp) = &self.temp else {
            return Err(io_err(&target, "write")(io::Error::other(
                "already committed",
            )));
        };
        let file = File::create(temp.join(name)).map_err(io_err(&target, "write"))?;
        Ok((file, target))
    }

    /// The hidden folder, for work a long job keeps on disk rather than in memory: anything
    /// put there that was not [`add`](Staged::add)ed goes with the folder; `None` once
    /// committed.
    pub fn scratch_dir(&self) -> Option<&Path> {
        self.temp.as_deref()
    }

    /// Remove file `name` from `dir` when committing (a previous run's file the new set does
    /// not replace); put back if the commit fails.
    pub fn remove_on_commit(&mut self, name: &str) {
        if !self.names.iter().any(|n| n == name) && !self.stale.iter().any(|n| n == name) {
            self.stale.push(name.to_string());
        }
    }

    /// Move every staged file into place, all or nothing. Returns their paths in the order
    /// they were added.
    pub fn commit(mut self) -> Result<Vec<PathBuf>, OutputError> {
        let Some(temp) = self.temp.take() else {
            return Ok(Vec::new());
        };
        let stale: Vec<String> = self
            .stale
            .iter()
            .filter(|n| fs::symlink_metadata(self.dir.join(n)).is_ok_and(|m| m.is_file()))
            .cloned()
            .collect();
        finish(&self.dir, temp, &self.names, &stale, &mut |_| Ok(()))
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        if let Some(temp) = self.temp.take() {
            let _ = fs::remove_dir_all(temp);
            self.created.remove_if_empty();
        }
    }
}

/// Checks an output folder before any work is done: `dir` is a directory, or does not exist
/// and its nearest existing ancestor is a directory it can be created in; files can be
/// created there; none of `files` (names inside `dir`) is a directory. Creates nothing (a probe
/// file is made and removed to test that the place is writable).
pub fn check_out_dir(dir: &Path, files: &[&str]) -> Result<(), OutputError> {
    let mut place = dir.to_path_buf();
    loop {
        match fs::metadata(&place) {
            Ok(m) if m.is_dir() => break,
            Ok(m) => {
                return Err(OutputError::NotADirectory {
                    path: place,
                    kind: kind_of(&m),
                })
            }
            Err(e)
                if matches!(
                    e.kind(),
                    io::ErrorKind::NotFound | io::ErrorKind::NotADirectory
                ) =>
            {
                // `dir` will be created: its parent must exist or be created too (and if a
                // file stands in the way, the walk up finds it).
                match place.parent() {
                    Some(p) if !p.as_os_str().is_empty() => place = p.to_path_buf(),
                    Some(_) if place != Path::new(".") => place = PathBuf::from("."),
                    _ => return Err(io_err(&place, "read")(e)),
                }
            }
            Err(e) => return Err(io_err(&place, "read")(e)),
        }
    }
    probe_writable(&place).map_err(|error| OutputError::Unwritable {
        path: place.clone(),
        error,
    })?;
    if place == dir {
        for name in files {
            let target = dir.join(name);
            if fs::symlink_metadata(&target).is_ok_and(|m| m.is_dir()) {
                return Err(OutputError::TargetIsDirectory { path: target });
            }
        }
    }
    Ok(())
}

/// Checks an output file before any work is done: `path` does not exist or is a regular file
/// (never a device such as `/dev/null`, a FIFO or a directory, which writing would replace),
/// and its folder exists and files can be created in it.
pub fn check_out_file(path: &Path) -> Result<(), OutputError> {
    match fs::metadata(path) {
        Ok(m) if m.is_file() => {}
        Ok(m) if m.is_dir() => {
            return Err(OutputError::TargetIsDirectory {
                path: path.to_path_buf(),
            })
        }
        Ok(m) => {
            return Err(OutputError::Unwritable {
                path: path.to_path_buf(),
                error: io::Error::new(
                    io::ErrorKind::InvalidInput,
                    format!(
                        "it is {}, not a regular file; it is never replaced",
                        kind_of(&m)
                    ),
                ),
            })
        }
        Err(e) if e.kind() == io::ErrorKind::NotFound => {}
        Err(e) => return Err(io_err(path, "read")(e)),
    }
    let folder = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    match fs::metadata(&folder) {
        Ok(m) if m.is_dir() => {}
        Ok(m) => {
            return Err(OutputError::NotADirectory {
                path: folder,
                kind: kind_of(&m),
            })
        }
        Err(e) => return Err(io_err(&folder, "use as the output folder")(e)),
    }
    probe_writable(&folder).map_err(|error| OutputError::Unwritable {
        path: folder,
        error,
    })
}

/// Creates and removes a hidden file in `dir`: whether files can be created there (permissions,
/// a read-only file system, a full disk's inode table), whoever runs this.
fn probe_writable(dir: &Path) -> io::Result<()> {
    static NEXT: AtomicU64 = AtomicU64::new(0);
    let probe = dir.join(format!(
        ".dbuffer-probe-{}-{}",
        std::process::id(),
        NEXT.fetch_add(1, Ordering::Relaxed)
    ));
    fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe)?;
    fs::remove_file(&probe)
}

/// The folders one `create_dir_all` made, to take them away again after a failure.
#[derive(Debug, Default)]
pub struct NewDirs {
    /// Outermost first.
    created: Vec<PathBuf>,
}

impl NewDirs {
    /// Creates `dir` and the ancestors it lacks; remembers which it made.
    pub fn create(dir: &Path) -> io::Result<NewDirs> {
        let mut missing = Vec::new();
        let mut p = dir;
        while !p.as_os_str().is_empty() && fs::symlink_metadata(p).is_err() {
            missing.push(p.to_path_buf());
            match p.parent() {
                Some(parent) => p = parent,
                None => break,
            }
        }
        missing.reverse();
        let mut made = NewDirs::default();
        for d in missing {
            match fs::create_dir(&d) {
                Ok(()) => made.created.push(d),
                Err(e) if e.kind() == io::ErrorKind::AlreadyExists && d.is_dir() => {}
                Err(e) => {
                    made.remove_if_empty();
                    return Err(e);
                }
            }
        }
        Ok(made)
    }

    /// Removes the folders made, innermost first, as long as each is empty.
    pub fn remove_if_empty(&self) {
        for d in self.created.iter().rev() {
            if fs::remove_dir(d).is_err() {
                break;
            }
        }
    }
}

/// A fresh `dir/.dbuffer-render-PID-N`.
pub(super) fn create_temp_dir(dir: &Path) -> Result<PathBuf, OutputError> {
    static NEXT: AtomicU64 = AtomicU64::new(0);
    let mut last = dir.join(TEMP_PREFIX);
    for _ in 0..100 {
        let n = NEXT.fetch_add(1, Ordering::Relaxed);
        last = dir.join(format!("{TEMP_PREFIX}{}-{n}", std::process::id()));
        match fs::create_dir(&last) {
            Ok(()) => return Ok(last),
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(io_err(&last, "create a temporary directory")(e)),
        }
    }
    Err(io_err(&last, "create a temporary directory")(
        io::Error::new(io::ErrorKind::AlreadyExists, "100 names tried, all taken"),
    ))
}

enum InstallError {
    /// Failed; the output folder is as it was.
    RolledBack(OutputError),
    /// Failed, and putting the previous files back failed too.
    Stuck(OutputError, io::Error),
}

/// Back up the previous files into `temp`, then rename the new ones over them and remove the
/// `stale` ones; on failure, put the previous files back. Step indices count `names` first,
/// then `stale`.
fn install(
    dir: &Path,
    temp: &Path,
    names: &[String],
    stale: &[String],
    fault: &mut Fault<'_>,
) -> Result<Vec<PathBuf>, InstallError> {
    let backup_of = |name: &str| temp.join(format!("{name}.previous"));
    let all: Vec<&String> = names.iter().chain(stale).collect();
    let mut had_previous = vec![false; all.len()];
    for (i, name) in all.iter().enumerate() {
        let target = dir.join(name);
        match fs::symlink_metadata(&target) {
            Ok(_) => {
                let backup = backup_of(name);
                fault(Step::Backup(i))
                    .and_then(|()| {
                        fs::hard_link(&target, &backup)
                            .or_else(|_| fs::copy(&target, &backup).map(drop))
                    })
                    .map_err(|e| InstallError::RolledBack(io_err(&target, "back up")(e)))?;
                had_previous[i] = true;
            }
            Err(e) if e.kind() == io::ErrorKind::NotFound => {}
            Err(e) => return Err(InstallError::RolledBack(io_err(&target, "read")(e))),
        }
    }
    let mut paths = Vec::with_capacity(names.len());
    for (i, name) in all.iter().enumerate() {
        let target = dir.join(name);
        let installing = i < names.len();
        let moved = fault(Step::Install(i)).and_then(|()| {
            if installing {
                fs::rename(temp.join(name), &target)
            } else {
                fs::remove_file(&target)
            }
        });
        if let Err(e) = moved {
            let action = if installing {
                "move into place"
            } else {
                "remove"
            };
            let cause = io_err(&target, action)(e);
            // Undo steps 0..i, last first.
            let mut undo = Ok(());
            for (j, name) in all.iter().enumerate().take(i).rev() {
                let target = dir.join(name);
                let step = if had_previous[j] {
                    fs::rename(backup_of(name), &target)
                } else {
                    fs::remove_file(&target)
                };
                if undo.is_ok() {
                    undo = step;
                }
            }
            return Err(match undo {
                Ok(()) => InstallError::RolledBack(cause),
                Err(rollback) => InstallError::Stuck(cause, rollback),
            });
        }
        if installing {
            paths.push(target);
        }
    }
    Ok(paths)
}
