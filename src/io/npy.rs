//! NumPy `.npy` arrays (little-endian float64, C order).

use super::{write_atomic, OutputError};
use std::path::Path;

/// Writes a little-endian float64 `.npy` array of the given shape, C (row-major) order.
/// `shape` may be empty for a scalar; its product must equal `data.len()`.
pub fn write_npy(path: &Path, data: &[f64], shape: &[usize]) -> Result<(), OutputError> {
    let count: usize = shape.iter().product();
    if count != data.len() {
        return Err(OutputError::data(
            path,
            format!(
                "shape {shape:?} holds {count} values but {} were given",
                data.len()
            ),
        ));
    }
    npy_bytes(data, shape)
        .map_err(|e| OutputError::io("encode .npy for", path, e))
        .and_then(|bytes| write_atomic(path, &bytes))
}

/// Encodes `data` with `shape` as the bytes of an `.npy` file.
fn npy_bytes(data: &[f64], shape: &[usize]) -> std::io::Result<Vec<u8>> {
    use npyz::WriterBuilder;
    let shape: Vec<u64> = shape.iter().map(|&s| s as u64).collect();
    let mut bytes = Vec::new();
    let mut writer = npyz::WriteOptions::new()
        .default_dtype()
        .shape(&shape)
        .writer(&mut bytes)
        .begin_nd()?;
    writer.extend(data.iter().copied())?;
    writer.finish()?;
    Ok(bytes)
}
