//! Outputs of a run: summary.json (the contract's keys and more).

pub mod summary;

use crate::{Error, Result};
use std::path::Path;

/// Writes `bytes` to `path` atomically (temporary file, then rename), so a reader or an
/// interrupted run never sees half a file.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let tmp = path.with_extension("tmp");
    std::fs::write(&tmp, bytes).map_err(|e| Error::io(&tmp, e))?;
    std::fs::rename(&tmp, path).map_err(|e| Error::io(path, e))
}
