//! Opening input files safely: every loader (scene, PLY, OBJ, MTL, shader
//! script, texture image) goes through here, so that a FIFO, a device such as
//! `/dev/zero`, a folder or a file larger than the loader's cap is refused
//! with a sentence before a single byte is read.
//!
//! The check is done twice: on the path before opening (opening a FIFO for
//! reading would block until a writer appears) and on the opened handle
//! (the path may have been swapped in between). Reading is bounded by the
//! cap as well, so a file that grows while being read cannot run memory out.

use std::fs::File;
use std::io::Read;
use std::path::Path;

/// Why a file cannot be read, as a sentence fragment ("no such file", "it is
/// a FIFO, not a regular file", ...). Never quotes the file's contents.
pub type Why = String;

/// What kind of non-regular file a path is, for the error.
fn kind(meta: &std::fs::Metadata) -> &'static str {
    use std::os::unix::fs::FileTypeExt;
    let t = meta.file_type();
    if t.is_dir() {
        "a folder"
    } else if t.is_fifo() {
        "a FIFO"
    } else if t.is_char_device() || t.is_block_device() {
        "a device"
    } else if t.is_socket() {
        "a socket"
    } else {
        "not a regular file"
    }
}

fn check(meta: &std::fs::Metadata, max: u64) -> Result<u64, Why> {
    if meta.is_dir() {
        return Err("it is a folder".to_string());
    }
    if !meta.is_file() {
        return Err(format!("it is {}, not a regular file", kind(meta)));
    }
    if meta.len() > max {
        return Err(format!("{} bytes, more than the {max} accepted", meta.len()));
    }
    Ok(meta.len())
}

/// Checks that `path` is a regular file of at most `max` bytes without opening it.
pub fn check_regular(path: &Path, max: u64) -> Result<u64, Why> {
    let meta = std::fs::metadata(path).map_err(|e| io_reason(&e))?;
    check(&meta, max)
}

/// Opens `path` for reading after checking that it is a regular file of at
/// most `max` bytes; returns the file and its length.
pub fn open_regular(path: &Path, max: u64) -> Result<(File, u64), Why> {
    check_regular(path, max)?;
    // Without blocking: a path swapped for a FIFO after the check above
    // would otherwise wait for a writer inside `open`; the type is checked
    // again on the handle.
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    std::os::unix::fs::OpenOptionsExt::custom_flags(&mut options, libc::O_NONBLOCK);
    let file = options.open(path).map_err(|e| io_reason(&e))?;
    let len = check(&file.metadata().map_err(|e| io_reason(&e))?, max)?;
    Ok((file, len))
}

/// The bytes of a regular file of at most `max` bytes.
pub fn read_bytes(path: &Path, max: u64) -> Result<Vec<u8>, Why> {
    let (file, len) = open_regular(path, max)?;
    let mut bytes = Vec::with_capacity(len as usize);
    file.take(max.saturating_add(1)).read_to_end(&mut bytes).map_err(|e| io_reason(&e))?;
    if bytes.len() as u64 > max {
        return Err(format!("it grew past the {max} bytes accepted while being read"));
    }
    Ok(bytes)
}

/// The text of a regular UTF-8 file of at most `max` bytes.
pub fn read_text(path: &Path, max: u64) -> Result<String, Why> {
    String::from_utf8(read_bytes(path, max)?).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let line = e.as_bytes()[..at].iter().filter(|&&b| b == b'\n').count() + 1;
        format!("it is not UTF-8 text (invalid byte on line {line}, at offset {at})")
    })
}

/// The reason of an I/O error without the "(os error N)" noise.
pub fn io_reason(e: &std::io::Error) -> String {
    match e.kind() {
        std::io::ErrorKind::NotFound => "no such file".to_string(),
        std::io::ErrorKind::PermissionDenied => "permission denied".to_string(),
        _ => {
            let s = e.to_string();
            match s.find(" (os error") {
                Some(i) => s[..i].to_string(),
                None => s,
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn devices_folders_and_big_files_are_refused_before_reading() {
        let zero = read_bytes(Path::new("/dev/zero"), 1 << 20).unwrap_err();
        assert_eq!(zero, "it is a device, not a regular file");
        let dir = tempfile::tempdir().unwrap();
        assert_eq!(read_bytes(dir.path(), 10).unwrap_err(), "it is a folder");
        let f = dir.path().join("f.txt");
        std::fs::write(&f, "0123456789a").unwrap();
        assert!(read_bytes(&f, 10).unwrap_err().contains("11 bytes, more than the 10"));
        assert_eq!(read_text(&f, 11).unwrap(), "0123456789a");
        std::fs::write(&f, b"ok\n\xff").unwrap();
        assert!(read_text(&f, 11).unwrap_err().contains("line 2"));
    }

    #[test]
    fn a_fifo_is_refused_without_blocking() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("pipe");
        let made = std::process::Command::new("mkfifo").arg(&p).status().unwrap();
        assert!(made.success());
        assert_eq!(read_bytes(&p, 10).unwrap_err(), "it is a FIFO, not a regular file");
    }
}
