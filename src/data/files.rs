//! Reading input files without trusting them: only regular files, their
//! size taken from metadata and checked before a byte is read, so a FIFO,
//! a device such as /dev/zero, or a file far larger than expected is
//! refused rather than read into memory or waited on forever.

use std::fs::File;
use std::io::{Error, ErrorKind, Read};
use std::path::Path;

/// The most a rig, manifest or color map file may hold: far more than
/// any real one, far less than would hurt.
pub const TEXT_LIMIT: u64 = 16 << 20;

/// Opens `path` if it is a regular file; returns it with its length.
pub fn open_regular(path: &Path) -> Result<(File, u64), Error> {
    let not_regular = || {
        Error::new(
            ErrorKind::InvalidInput,
            "not a regular file (a directory, FIFO or device cannot be read as one)",
        )
    };
    // Looked at before opening: opening a FIFO blocks until a writer comes.
    if !std::fs::metadata(path)?.is_file() {
        return Err(not_regular());
    }
    let file = File::open(path)?;
    let meta = file.metadata()?;
    if !meta.is_file() {
        return Err(not_regular());
    }
    Ok((file, meta.len()))
}

/// The whole of a regular file of at most `limit` bytes.
pub fn read_limited(path: &Path, limit: u64) -> Result<Vec<u8>, Error> {
    let (file, len) = open_regular(path)?;
    if len > limit {
        return Err(Error::new(
            ErrorKind::InvalidInput,
            format!("{len} bytes is more than the {limit} such a file may hold"),
        ));
    }
    read_len(file, len)
}

/// `read_limited` as UTF-8 text.
pub fn read_text(path: &Path, limit: u64) -> Result<String, Error> {
    String::from_utf8(read_limited(path, limit)?)
        .map_err(|e| Error::new(ErrorKind::InvalidData, format!("not UTF-8 text: {e}")))
}

/// Exactly `len` bytes of `file`, its length by metadata; the buffer is
/// reserved fallibly, so a size that cannot be had is an error, not an
/// abort, and a file that changed size while read is noticed.
pub fn read_len(file: File, len: u64) -> Result<Vec<u8>, Error> {
    let too_large = || {
        Error::new(
            ErrorKind::OutOfMemory,
            format!("cannot hold {len} bytes in memory"),
        )
    };
    let n = usize::try_from(len).map_err(|_| too_large())?;
    let mut bytes = Vec::new();
    bytes.try_reserve_exact(n).map_err(|_| too_large())?;
    file.take(len + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 != len {
        return Err(Error::new(
            ErrorKind::UnexpectedEof,
            format!(
                "the file changed size while read ({len} bytes by metadata, {} read)",
                bytes.len()
            ),
        ));
    }
    Ok(bytes)
}

/// Where `needle` first occurs in `haystack`.
pub fn find(haystack: &[u8], needle: &[u8]) -> Option<usize> {
    haystack.windows(needle.len()).position(|w| w == needle)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn devices_directories_and_oversized_files_are_refused_before_reading() {
        for special in ["/dev/zero", "/dev/null", "/tmp"] {
            let e = read_limited(Path::new(special), 1 << 20).unwrap_err();
            assert!(
                e.to_string().contains("not a regular file"),
                "{special}: {e}"
            );
        }
        let dir = std::env::temp_dir().join(format!("caveray_files_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        // A FIFO with no writer: opening it would block forever.
        let fifo = dir.join("fifo");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        assert!(
            made.is_ok_and(|s| s.success()),
            "mkfifo (coreutils) is needed"
        );
        let e = read_limited(&fifo, 1 << 20).unwrap_err();
        assert!(e.to_string().contains("not a regular file"), "fifo: {e}");
        let big = dir.join("big");
        std::fs::write(&big, vec![b'x'; 2000]).unwrap();
        let e = read_limited(&big, 1000).unwrap_err();
        assert_eq!(
            e.to_string(),
            "2000 bytes is more than the 1000 such a file may hold"
        );
        assert_eq!(read_limited(&big, 2000).unwrap().len(), 2000);
        std::fs::write(&big, [0xffu8, 0xfe]).unwrap();
        assert!(read_text(&big, 10)
            .unwrap_err()
            .to_string()
            .contains("not UTF-8"));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
