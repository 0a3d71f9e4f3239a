//! Pretty-printed JSON.

use super::{write_atomic, OutputError};
use serde::Serialize;
use std::path::Path;

/// Writes `value` as pretty-printed JSON (with a trailing newline).
pub fn write_json<T: Serialize + ?Sized>(path: &Path, value: &T) -> Result<(), OutputError> {
    let mut bytes = serde_json::to_vec_pretty(value).map_err(|source| OutputError::Json {
        path: path.to_path_buf(),
        source,
    })?;
    bytes.push(b'\n');
    write_atomic(path, &bytes)
}
