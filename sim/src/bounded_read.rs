//! Reading a file a user names (a scenario, a URDF) without trusting it to be small or even a
//! file: one reader for every such place, so the rule is the same everywhere.

use std::io::Read as _;
use std::path::Path;

/// Why [`read_regular_file`] read nothing.
#[derive(Debug, thiserror::Error)]
pub enum BoundedReadError {
    /// A device, pipe or folder: `/dev/zero` never ends, a FIFO blocks.
    #[error("not a regular file")]
    NotAFile,
    /// Over the limit, by its size before reading or by what the read found.
    #[error("larger than {limit_bytes} bytes")]
    TooLarge {
        /// The limit the caller set.
        limit_bytes: u64,
    },
    /// The file system said no.
    #[error(transparent)]
    Io(#[from] std::io::Error),
}

/// The bytes of `path` if it is a regular file of at most `limit_bytes`. The type is checked
/// before opening (opening a FIFO without a writer blocks), the size before reading, and the
/// read itself stops at the limit in case the file grows meanwhile.
pub fn read_regular_file(path: &Path, limit_bytes: u64) -> Result<Vec<u8>, BoundedReadError> {
    let meta = std::fs::metadata(path)?;
    if !meta.is_file() {
        return Err(BoundedReadError::NotAFile);
    }
    if meta.len() > limit_bytes {
        return Err(BoundedReadError::TooLarge { limit_bytes });
    }
    let mut bytes = Vec::new();
    std::fs::File::open(path)?
        .take(limit_bytes + 1)
        .read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit_bytes {
        return Err(BoundedReadError::TooLarge { limit_bytes });
    }
    Ok(bytes)
}

/// The text of `path` ([`read_regular_file`]), or why not in words for a user: `what` names
/// the kind of file in the message about its size ("larger than 1 MiB, the limit for a robot
/// file (is it one?)").
pub fn read_text_file(path: &Path, limit_bytes: u64, what: &str) -> Result<String, String> {
    let bytes = read_regular_file(path, limit_bytes).map_err(|error| match error {
        BoundedReadError::NotAFile => "not a regular file".to_owned(),
        BoundedReadError::TooLarge { limit_bytes } => {
            let limit = if limit_bytes % (1024 * 1024) == 0 {
                format!("{} MiB", limit_bytes / (1024 * 1024))
            } else {
                format!("{limit_bytes} bytes")
            };
            format!("larger than {limit}, the limit for a {what} (is it one?)")
        }
        BoundedReadError::Io(e) => format!("cannot read: {e}"),
    })?;
    String::from_utf8(bytes).map_err(|_| "not UTF-8 text".to_owned())
}
