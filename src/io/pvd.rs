//! ParaView collections (`.pvd`): a time series of `.vtu` snapshots that ParaView opens as
//! one animated data set.

use super::vtu::xml_attr;
use super::{write_atomic, OutputError};
use std::fmt::Write as _;
use std::path::Path;

/// Writes the collection `path` listing `frames` as `(time_s, file)`, in the order given
/// (times must be finite). A file under the collection's directory is listed relative to
/// it, as ParaView resolves it, so the directory can be moved whole; others as given.
/// Rewriting the collection after each snapshot keeps it readable while a run goes on.
pub fn write_pvd(path: &Path, frames: &[(f64, &Path)]) -> Result<(), OutputError> {
    if let Some(i) = frames.iter().position(|(t, _)| !t.is_finite()) {
        return Err(OutputError::data(
            path,
            format!("frame {i} has a non-finite time {}", frames[i].0),
        ));
    }
    let dir = path.parent().unwrap_or(Path::new(""));
    let mut xml = String::from("<?xml version=\"1.0\"?>\n");
    xml.push_str("<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n");
    xml.push_str("  <Collection>\n");
    for (time_s, file) in frames {
        let listed = file.strip_prefix(dir).unwrap_or(file);
        let _ = writeln!(
            xml,
            "    <DataSet timestep=\"{time_s:e}\" group=\"\" part=\"0\" file=\"{}\"/>",
            xml_attr(&listed.to_string_lossy())
        );
    }
    xml.push_str("  </Collection>\n</VTKFile>\n");
    write_atomic(path, xml.as_bytes())
}
