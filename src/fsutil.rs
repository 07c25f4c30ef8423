//! Files in and out, defensively.
//!
//! - **Reading** ([`open_regular`], [`read_regular`]): only regular files (after following
//!   symlinks), checked before a byte is read, so a directory, a FIFO (which would block), a
//!   device (`/dev/zero` would never end) or a socket is refused; and never more than a budget
//!   of bytes, checked from the metadata first and enforced while reading.
//! - **Writing** ([`write_atomic`]): write a temporary file beside the target, flush it to disk,
//!   then rename it over the target (atomic on one file system), never over something that is
//!   not a regular file.

use std::fs::{self, File};
use std::io::{self, Read, Write};
use std::path::{Path, PathBuf};

/// Why a file was not read. The messages start lower case and name no path: the caller adds it.
/// Each message includes its cause's (no `source()`, so that `{:#}` does not repeat it).
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    /// Opening or reading failed (missing, permissions, ...).
    #[error("cannot read the file: {0}")]
    Io(io::Error),
    /// Not a regular file: refused before reading.
    #[error("is {kind}, not a regular file: refused without reading it")]
    NotRegular { kind: &'static str },
    /// Larger than the budget (from its metadata, or while reading if it grew).
    #[error(
        "is {size} bytes, more than the budget of {} for {what} ({name})",
        crate::budget::bytes(*limit)
    )]
    TooLarge {
        size: u64,
        limit: u64,
        what: &'static str,
        name: &'static str,
    },
}

/// A limit on the bytes read from one file: `limit` bytes, called `name` in the budget
/// (`crate::budget`), for `what` ("a scene file").
#[derive(Clone, Copy, Debug)]
pub struct ByteBudget {
    pub limit: u64,
    pub name: &'static str,
    pub what: &'static str,
}

/// What kind of thing `meta` describes, for messages: "a regular file", "a directory", "a FIFO
/// (named pipe)", ... The one answer every message that names a file's kind gives: reading
/// refuses anything but a regular file before a byte is read ([`open_regular`]), writing never
/// replaces anything but one ([`check_replaceable`]), and `--out` is checked before any work
/// (`output::check_out_dir`, `output::check_out_file`) — each says exactly what it found. The
/// callers take `fs::metadata` (symlinks followed), so "a symbolic link" shows only for a
/// `symlink_metadata`.
pub(crate) fn kind_of(meta: &fs::Metadata) -> &'static str {
    let t = meta.file_type();
    if t.is_file() {
        return "a regular file";
    }
    if t.is_dir() {
        return "a directory";
    }
    if t.is_symlink() {
        return "a symbolic link";
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return "a FIFO (named pipe)";
        }
        if t.is_char_device() {
            return "a character device";
        }
        if t.is_block_device() {
            return "a block device";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    "a special file"
}

/// Opens `path` for reading if it is a regular file (after following symlinks) of at most
/// `budget.limit` bytes; returns the file and its size. Nothing is read. The type is checked
/// from the path's metadata before opening (so a FIFO is never opened, which could block) and
/// again on the opened handle.
pub fn open_regular(path: &Path, budget: ByteBudget) -> Result<(File, u64), ReadError> {
    let check = |meta: &fs::Metadata| {
        if !meta.is_file() {
            return Err(ReadError::NotRegular {
                kind: kind_of(meta),
            });
        }
        if meta.len() > budget.limit {
            return Err(ReadError::TooLarge {
                size: meta.len(),
                limit: budget.limit,
                what: budget.what,
                name: budget.name,
            });
        }
        Ok(meta.len())
    };
    check(&fs::metadata(path).map_err(ReadError::Io)?)?;
    let file = File::open(path).map_err(ReadError::Io)?;
    let size = check(&file.metadata().map_err(ReadError::Io)?)?;
    Ok((file, size))
}

/// Reads the whole of `path` if [`open_regular`] accepts it, never more than `budget.limit`
/// bytes (a file that grows past it while being read is refused too).
pub fn read_regular(path: &Path, budget: ByteBudget) -> Result<Vec<u8>, ReadError> {
    let (file, size) = open_regular(path, budget)?;
    let mut bytes = Vec::with_capacity(usize::try_from(size).unwrap_or(0));
    file.take(budget.limit.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(ReadError::Io)?;
    if bytes.len() as u64 > budget.limit {
        return Err(ReadError::TooLarge {
            size: bytes.len() as u64,
            limit: budget.limit,
            what: budget.what,
            name: budget.name,
        });
    }
    Ok(bytes)
}

/// Write `bytes` to `path` atomically. On error the previous file, if any, is untouched and the
/// temporary file is removed. A `path` that exists and is not a regular file (a directory, a
/// device such as `/dev/null`, a FIFO) is refused: renaming over it would replace it.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> io::Result<()> {
    check_replaceable(path)?;
    let tmp = temp_path(path);
    let result = (|| {
        let mut f = fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result
}

/// `Ok` if `path` does not exist or is a regular file (or a symlink to one, which is replaced by
/// the new file); otherwise an error saying what it is.
pub fn check_replaceable(path: &Path) -> io::Result<()> {
    match fs::metadata(path) {
        Ok(meta) if meta.is_file() => Ok(()),
        Ok(meta) => Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("it exists and is {}, not a regular file", kind_of(&meta)),
        )),
        Err(e) if e.kind() == io::ErrorKind::NotFound => Ok(()),
        Err(e) => Err(e),
    }
}

/// `dir/.name.tmp-PID` beside `path`.
fn temp_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "file".into());
    path.with_file_name(format!(".{name}.tmp-{}", std::process::id()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn replaces_and_keeps_the_old_file_on_failure() {
        let dir = std::env::temp_dir().join(format!("dbuffer-fsutil-{}", std::process::id()));
        fs::create_dir_all(&dir).expect("temp dir");
        let file = dir.join("scene.toml");
        write_atomic(&file, b"one").expect("first write");
        write_atomic(&file, b"two").expect("second write");
        assert_eq!(fs::read(&file).expect("read"), b"two");
        // Writing into a directory that does not exist fails and leaves nothing behind.
        let missing = dir.join("no-such-dir").join("x.toml");
        assert!(write_atomic(&missing, b"three").is_err());
        // A target that is a directory cannot be replaced: the old content stays.
        let blocked = dir.join("blocked");
        fs::create_dir_all(&blocked).expect("dir");
        assert!(write_atomic(&blocked, b"four").is_err());
        assert!(blocked.is_dir());
        let leftovers: Vec<_> = fs::read_dir(&dir)
            .expect("list")
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().contains(".tmp-"))
            .collect();
        assert!(leftovers.is_empty(), "temporary files left: {leftovers:?}");
        let _ = fs::remove_dir_all(&dir);
    }

    /// One answer per kind, for reading and for writing alike: a regular file is named as one (an
    /// output folder that is a file says so, not "not a file"), a device or a FIFO by what it is
    /// (not "a device, FIFO or socket"), and a link seen without following it as a link.
    #[test]
    fn kinds_are_named_exactly() {
        let dir = std::env::temp_dir().join(format!("dbuffer-fsutil-kind-{}", std::process::id()));
        fs::create_dir_all(&dir).expect("temp dir");
        let file = dir.join("file");
        fs::write(&file, b"x").expect("write");
        let kind = |p: &Path| kind_of(&fs::metadata(p).expect("metadata"));
        assert_eq!(kind(&file), "a regular file");
        assert_eq!(kind(&dir), "a directory");
        #[cfg(unix)]
        {
            assert_eq!(kind(Path::new("/dev/null")), "a character device");
            let link = dir.join("link");
            let _ = fs::remove_file(&link);
            std::os::unix::fs::symlink(&file, &link).expect("symlink");
            assert_eq!(kind(&link), "a regular file", "followed");
            let meta = fs::symlink_metadata(&link).expect("symlink metadata");
            assert_eq!(kind_of(&meta), "a symbolic link");
            let fifo = dir.join("fifo");
            let _ = fs::remove_file(&fifo);
            let made = std::process::Command::new("mkfifo").arg(&fifo).status();
            if made.is_ok_and(|s| s.success()) {
                assert_eq!(kind(&fifo), "a FIFO (named pipe)");
                let e = check_replaceable(&fifo).unwrap_err().to_string();
                assert!(
                    e.contains("is a FIFO (named pipe), not a regular file"),
                    "{e}"
                );
            }
        }
        let _ = fs::remove_dir_all(&dir);
    }

    const TINY: ByteBudget = ByteBudget {
        limit: 8,
        name: "TEST_LIMIT",
        what: "a test file",
    };

    #[test]
    fn only_regular_files_within_the_budget_are_read() {
        let dir = std::env::temp_dir().join(format!("dbuffer-fsutil-read-{}", std::process::id()));
        fs::create_dir_all(&dir).expect("temp dir");
        let small = dir.join("small");
        fs::write(&small, b"12345678").expect("write");
        assert_eq!(read_regular(&small, TINY).expect("read"), b"12345678");
        let big = dir.join("big");
        fs::write(&big, b"123456789").expect("write");
        let e = read_regular(&big, TINY).unwrap_err().to_string();
        assert!(e.contains("TEST_LIMIT") && e.contains("8 bytes"), "{e}");
        let e = read_regular(&dir, TINY).unwrap_err().to_string();
        assert!(e.contains("a directory"), "{e}");
        #[cfg(unix)]
        {
            // /dev/zero never ends: refused from its metadata, before reading.
            let e = read_regular(Path::new("/dev/zero"), TINY)
                .unwrap_err()
                .to_string();
            assert!(e.contains("character device"), "{e}");
            let link = dir.join("zero-link");
            let _ = fs::remove_file(&link);
            std::os::unix::fs::symlink("/dev/zero", &link).expect("symlink");
            let e = read_regular(&link, TINY).unwrap_err().to_string();
            assert!(e.contains("character device"), "{e}");
            // Writing over something that is not a file is refused and leaves it alone (a FIFO
            // here: were the check to go, the test must not replace a real device node).
            let fifo = dir.join("fifo");
            let _ = fs::remove_file(&fifo);
            let made = std::process::Command::new("mkfifo").arg(&fifo).status();
            if made.is_ok_and(|s| s.success()) {
                let e = write_atomic(&fifo, b"x").unwrap_err().to_string();
                assert!(e.contains("not a regular file"), "{e}");
                assert!(fs::symlink_metadata(&fifo).is_ok_and(|m| !m.is_file()));
                let e = read_regular(&fifo, TINY).unwrap_err().to_string();
                assert!(e.contains("FIFO"), "{e}");
            }
            // Nor is a device checked by its path alone ever opened for writing.
            assert!(check_replaceable(Path::new("/dev/null")).is_err());
        }
        let _ = fs::remove_dir_all(&dir);
    }
}
