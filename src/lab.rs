//! Lab data for the experiment scripts: a lab directory of recorded responses read as a
//! recorded channel (see [`crate::trnews::RecordedChannel`]), and the list of drives still to
//! record that such a channel writes when it is asked for a drive it has no recording of.
//!
//! On a cracked (nonlinear) sample every drive after the chirp depends on earlier
//! recordings, so the lab works in phases: a script run stops at the first batch of
//! transmissions with unrecorded drives (the chirp; then the focusing drives, with their
//! inverses for pulse inversion; then the delayed drives s(t) + a s(t - tau), eqs 10-11),
//! writes every missing drive of that batch under `OUT/to_record/` with the list
//! [`TO_RECORD_MANIFEST`], and ends with one error saying how many drives to play and how to
//! add the recordings. Rerunning after adding them proceeds to the next phase.
//!
//! A lab directory holds [`LAB_MANIFEST`]: `{"recordings": [{"sent": FILE, "received":
//! FILE}, ...]}`, paths relative to the directory; `sent` is the drive as a 1-D .npy,
//! `received` the receivers' traces as a 2-D .npy (one row per receiver, from the drive's
//! start), both on the channel's step `dt_s`. A drive matches a recording when it has the
//! same number of samples and a relative L2 difference of at most
//! [`crate::trnews::RecordedChannel::MATCH`]. A drive on another step is first resampled to
//! `dt_s` ([`crate::trnews::Responder::respond`]); a drive of another length (even one
//! zero-padded) never matches and is listed to record. A recording longer than asked for is cut; a shorter one
//! is an error giving the length needed.

use crate::error::{Error, Result};
#[cfg(feature = "io")]
use crate::input::{InputError, InputRoot};
use crate::io::OutputRoot;
use crate::signal::Signal;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// The manifest of a lab directory: the recordings it holds.
pub const LAB_MANIFEST: &str = "recordings.json";
/// The directory under the output directory that receives the drives to record.
pub const TO_RECORD_DIR: &str = "to_record";
/// The list of drives to record, in [`TO_RECORD_DIR`].
pub const TO_RECORD_MANIFEST: &str = "to_record.json";

/// What the lab does with the list, written into it.
const HOW: &str = "for each drive: copy `sent` into the lab directory, play it, record every \
     receiver from the drive's start for at least record_s (record_samples samples on step \
     dt_s), save the traces there as `received` (2-D float .npy, one row per receiver), add \
     {\"sent\": ..., \"received\": ...} to the lab directory's recordings.json, then rerun the \
     same command";

/// The contents of [`LAB_MANIFEST`].
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
#[cfg(feature = "io")]
struct LabManifest {
    recordings: Vec<RecordingFiles>,
}

/// One recording of a lab directory: the files of the drive sent and of the traces received.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
#[cfg(feature = "io")]
pub struct RecordingFiles {
    /// The drive, a 1-D .npy on the channel's step.
    pub sent: String,
    /// The receivers' traces, a 2-D .npy (one row per receiver) on the same step.
    pub received: String,
}

/// Largest data file read (the file and its values are held at once): a quarter of the
/// memory limit, as for the scripts' own reads.
#[cfg(feature = "io")]
fn read_limit() -> (u64, &'static str) {
    (
        crate::budget::memory_limit() / 4,
        "a quarter of --max-memory",
    )
}

/// An input error as the library's error.
#[cfg(feature = "io")]
fn input(e: InputError) -> Error {
    Error::Named(e.to_string())
}

/// The bytes of `rel` beneath `root`, `None` when it does not exist.
#[cfg(feature = "io")]
fn read_if_present(root: &InputRoot, rel: &Path) -> Result<Option<Vec<u8>>> {
    let (limit, why) = read_limit();
    match root.read(&rel.to_string_lossy(), limit, why) {
        Ok(bytes) => Ok(Some(bytes)),
        Err(InputError::Io { source, .. }) if source.kind() == std::io::ErrorKind::NotFound => {
            Ok(None)
        }
        Err(e) => Err(input(e)),
    }
}

/// Traces from the .npy file `rel` beneath `root` on step `dt_s`: a 1-D array is one trace,
/// a 2-D array one trace per row (per receiver). For measured impulse responses and
/// recorded traces.
#[cfg(feature = "io")]
pub fn read_traces(root: &InputRoot, rel: &str, dt_s: f64) -> Result<Vec<Signal>> {
    let (limit, why) = read_limit();
    let bytes = root.read(rel, limit, why).map_err(input)?;
    let table = crate::input::parse_npy(&root.path().join(rel), &bytes).map_err(input)?;
    let row = table.shape.last().copied().unwrap_or(0);
    table
        .values
        .chunks(row.max(1))
        .map(|samples| Ok(Signal::new(dt_s, 0.0, samples.to_vec())?))
        .collect()
}

/// The drive in the 1-D .npy file `rel` beneath `root`, on step `dt_s`.
#[cfg(feature = "io")]
fn read_drive(root: &InputRoot, rel: &str, dt_s: f64) -> Result<Signal> {
    match read_traces(root, rel, dt_s)?.as_slice() {
        [drive] => Ok(drive.clone()),
        rows => Err(Error::invalid(
            "sent",
            rel,
            format!(
                "holds {} rows: a drive is a 1-D .npy array of samples",
                rows.len()
            ),
        )),
    }
}

/// One recorded transmission: the drive sent and what every receiver recorded.
#[derive(Clone, Debug)]
pub struct Recording {
    /// The drive signal sent.
    pub sent: Signal,
    /// One trace per receiver, from t = 0 on the drive's step.
    pub received: Vec<Signal>,
}

/// The recordings of the lab directory `dir` beneath `root`, on step `dt_s`: none when the
/// directory has no [`LAB_MANIFEST`] yet (before the first phase); an error when the
/// directory does not exist.
#[cfg(feature = "io")]
pub fn read_lab(root: &InputRoot, dir: &str, dt_s: f64) -> Result<Vec<Recording>> {
    if !root.is_dir(dir) {
        return Err(Error::invalid(
            "recordings",
            dir,
            format!(
                "is not a directory under the data directory {} (create it, empty, before \
                 the first phase)",
                root.path().display()
            ),
        ));
    }
    let manifest_path = Path::new(dir).join(LAB_MANIFEST);
    let Some(bytes) = read_if_present(root, &manifest_path)? else {
        return Ok(Vec::new());
    };
    let shown = root.path().join(&manifest_path);
    let json = crate::input::parse_json(&shown, &bytes).map_err(input)?;
    let manifest: LabManifest = serde_json::from_value(json).map_err(|e| {
        Error::Named(format!(
            "cannot read {}: {e} (expected {{\"recordings\": [{{\"sent\": FILE, \"received\": \
             FILE}}, ...]}})",
            shown.display()
        ))
    })?;
    manifest
        .recordings
        .iter()
        .map(|files| {
            let at = |name: &str| Path::new(dir).join(name).to_string_lossy().into_owned();
            Ok(Recording {
                sent: read_drive(root, &at(&files.sent), dt_s)?,
                received: read_traces(root, &at(&files.received), dt_s)?,
            })
        })
        .collect()
}

/// A drive asked for without a recording, and how long the lab must record it.
#[derive(Clone, Debug)]
struct Wanted {
    drive: Signal,
    record_s: f64,
}

/// One entry of [`TO_RECORD_MANIFEST`].
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct DriveToRecord {
    /// The drive's file (in [`TO_RECORD_DIR`]; copy it into the lab directory).
    pub sent: String,
    /// The file name to save the recorded traces under, in the lab directory.
    pub received: String,
    /// The drive's sample step (s): the channel's `dt_s`.
    pub dt_s: f64,
    /// Samples of the drive.
    pub samples: usize,
    /// Largest |drive sample|.
    pub peak: f64,
    /// Shortest recording that answers every request for this drive (s).
    pub record_s: f64,
    /// The same in samples on step `dt_s`.
    pub record_samples: usize,
}

/// The contents of [`TO_RECORD_MANIFEST`].
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ToRecordManifest {
    /// The lab directory (`--data` joined with `--set recordings=DIR`).
    pub lab: String,
    /// What to do with the drives.
    pub how: String,
    /// The drives to play and record; empty when the last run needed no new drive.
    pub drives: Vec<DriveToRecord>,
}

/// The drives a lab channel was asked for and has no recording of: written under the output
/// directory (`OUT/to_record/drive_<id>.npy`, id from the SHA-256 of the drive's step and
/// samples, and [`TO_RECORD_MANIFEST`]), each file whole (temporary file + rename).
#[derive(Debug)]
pub struct ToRecord {
    dir: PathBuf,
    root: Option<OutputRoot>,
    lab: String,
    wanted: Mutex<BTreeMap<String, Wanted>>,
}

impl ToRecord {
    /// The list for the lab directory `lab` (as shown in messages) under `out_dir`, written
    /// through `root` when given;
    /// writes the empty list, so that after a run that needed no new drive the list says so.
    pub fn new(out_dir: &Path, root: Option<OutputRoot>, lab: &str) -> Result<ToRecord> {
        let list = ToRecord {
            dir: out_dir.join(TO_RECORD_DIR),
            root,
            lab: lab.to_string(),
            wanted: Mutex::new(BTreeMap::new()),
        };
        list.write(&BTreeMap::new())?;
        Ok(list)
    }

    /// Adds `drive`, to be recorded for at least `record_s`.
    pub fn want(&self, drive: &Signal, record_s: f64) {
        let mut wanted = self.wanted.lock().unwrap_or_else(|p| p.into_inner());
        let entry = wanted.entry(drive_id(drive)).or_insert_with(|| Wanted {
            drive: drive.clone(),
            record_s,
        });
        entry.record_s = entry.record_s.max(record_s);
    }

    /// Writes every drive wanted so far and returns the error that stops the run, saying
    /// how many drives to play, where they are and how to add their recordings (or the
    /// error of a failed write).
    pub fn stop(&self) -> Error {
        let wanted = self
            .wanted
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .clone();
        if let Err(e) = self.write(&wanted) {
            return e;
        }
        let n = wanted.len();
        Error::Named(format!(
            "lab: {n} drive{} not recorded yet in '{}': play the drive{} listed in {} \
             (files beside it; each entry gives the step dt_s and the length record_s to \
             record), save each recording in '{}' under the entry's `received` name next to \
             a copy of its `sent` file, add {{\"sent\", \"received\"}} of each entry to {}/{}, \
             and rerun the same command",
            if n == 1 { " is" } else { "s are" },
            self.lab,
            if n == 1 { "" } else { "s" },
            self.dir.join(TO_RECORD_MANIFEST).display(),
            self.lab,
            self.lab,
            LAB_MANIFEST
        ))
    }

    /// Writes the drive files of `wanted` and the list naming them.
    fn write(&self, wanted: &BTreeMap<String, Wanted>) -> Result<()> {
        let mut drives = Vec::with_capacity(wanted.len());
        for (id, w) in wanted {
            let sent = format!("drive_{id}.npy");
            let d = &w.drive;
            self.within(|| crate::io::write_npy(&self.dir.join(&sent), &d.samples, &[d.len()]))?;
            drives.push(DriveToRecord {
                received: format!("drive_{id}_received.npy"),
                sent,
                dt_s: d.dt_s,
                samples: d.len(),
                peak: d.max_abs(),
                record_s: w.record_s,
                record_samples: (w.record_s / d.dt_s).round() as usize,
            });
        }
        let manifest = ToRecordManifest {
            lab: self.lab.clone(),
            how: HOW.into(),
            drives,
        };
        self.within(|| crate::io::write_json(&self.dir.join(TO_RECORD_MANIFEST), &manifest))?;
        Ok(())
    }

    /// Runs a write through the output root, when there is one.
    fn within<T>(&self, f: impl FnOnce() -> T) -> T {
        match &self.root {
            Some(root) => root.within(f),
            None => f(),
        }
    }
}

/// The first 16 hex digits of the SHA-256 of the drive's step and samples (their f64 bits):
/// the same drive always gets the same file name.
fn drive_id(drive: &Signal) -> String {
    use sha2::{Digest, Sha256};
    let mut h = Sha256::new();
    h.update(drive.dt_s.to_le_bytes());
    for v in &drive.samples {
        h.update(v.to_le_bytes());
    }
    h.finalize()[..8]
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}
