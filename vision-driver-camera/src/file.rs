//! Opening an image file that may be anything: only a regular file is read. A FIFO would block
//! the open until a writer comes (and then deliver whatever it writes), a device such as
//! `/dev/zero` never ends; both are refused without reading a byte.

use std::fs::File;
use std::path::Path;

/// Why a path was not opened as an image file.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum OpenError {
    /// The operating system refused (missing, no permission, …).
    #[error("{0}")]
    Io(#[from] std::io::Error),
    /// It exists but is not a regular file.
    #[error("it is a {kind}, not a regular file")]
    NotRegular {
        /// `FIFO`, `character device`, `block device`, `socket`, `folder`.
        kind: &'static str,
    },
}

/// Opens `path` for reading if it is a regular file. On Unix the open itself cannot block (it
/// is made with `O_NONBLOCK`, which a regular file ignores) and the check is on the opened file,
/// so a path swapped for a FIFO between a check and the open is still refused.
///
/// # Errors
/// [`OpenError::Io`] from the open, or [`OpenError::NotRegular`] naming what it is.
pub fn open_regular(path: &Path) -> Result<File, OpenError> {
    let file = open_without_blocking(path)?;
    let file_type = file.metadata()?.file_type();
    if file_type.is_file() {
        Ok(file)
    } else {
        Err(OpenError::NotRegular { kind: kind_of(file_type) })
    }
}

#[cfg(unix)]
fn open_without_blocking(path: &Path) -> std::io::Result<File> {
    use std::os::unix::fs::OpenOptionsExt;
    std::fs::OpenOptions::new().read(true).custom_flags(libc::O_NONBLOCK | libc::O_NOCTTY).open(path)
}

#[cfg(not(unix))]
fn open_without_blocking(path: &Path) -> std::io::Result<File> {
    File::open(path)
}

fn kind_of(file_type: std::fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if file_type.is_fifo() {
            return "FIFO";
        }
        if file_type.is_char_device() {
            return "character device";
        }
        if file_type.is_block_device() {
            return "block device";
        }
        if file_type.is_socket() {
            return "socket";
        }
    }
    if file_type.is_dir() {
        "folder"
    } else {
        "special file"
    }
}
