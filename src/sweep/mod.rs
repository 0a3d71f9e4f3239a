//! Sweeps as resumable work units: point files, shards and merges.
//!
//! A sweep maps a computation over parameter points (delayed TR-NEWS over delays and
//! amplitudes, `study::sweep` over any script-level points). Each finished point is written
//! whole (temporary file + rename, [`crate::io::write_atomic`]) to its own file
//! `points/<kind>/<key>.point` under the output directory. The key is the SHA-256 of a
//! canonical JSON serialisation of everything that determines the point: the crate version
//! and the hash of the sources it was built from, the kind of computation and its inputs
//! (scene spec, TR-NEWS spec, the point). A run looks each point up by key and computes
//! only the missing ones, so a sweep killed at any moment resumes where it stopped. The
//! shared first pass of a sweep (impulse response, chirp run, correlation, focusing signals)
//! is stored the same way by [`first_pass`].
//!
//! A point file is `postcard(PointFile)` followed by the SHA-256 of those bytes: a truncated
//! or corrupted file fails the checksum (or the decoding), is reported and recomputed, never
//! used. Values are encoded with postcard, which writes an f64 as its 8 bytes, and every
//! result is handed on as decoded from its file, so a sweep assembled from files written by
//! several processes is bit-identical to one computed in one piece.
//!
//! [`Role`] says what this process does with a sweep's missing points: compute them all,
//! compute its share (`--shard I/N`, or a Slurm array task) and stop, or compute none and
//! name them (`--merge`). A failed point is recorded with its error and the other points go
//! on; the sweep then fails naming it.

use crate::error::{Error, Result};
use crate::io::OutputRoot;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::cell::RefCell;
use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

mod nan;
pub use nan::{refuse_nan, refuse_non_finite};

/// First bytes of every point file's payload: the layout version of [`PointFile`].
const FORMAT: &str = "trnews-point 1";
/// Directory of the point files under the output directory.
pub const POINTS_DIR: &str = "points";

/// One share of a sharded sweep: point i belongs to shard `i mod count`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// 0-based shard number.
    pub index: usize,
    /// Number of shards.
    pub count: usize,
}

impl Shard {
    /// Parses `I/N` with 1 <= I <= N (as written on the command line, 1-based).
    pub fn parse(text: &str) -> std::result::Result<Shard, String> {
        let bad = || format!("--shard {text}: expected I/N with 1 <= I <= N, e.g. 2/3");
        let (i, n) = text.split_once('/').ok_or_else(bad)?;
        let (i, n) = (
            i.trim().parse::<usize>().map_err(|_| bad())?,
            n.trim().parse::<usize>().map_err(|_| bad())?,
        );
        if i == 0 || i > n {
            return Err(bad());
        }
        Ok(Shard {
            index: i - 1,
            count: n,
        })
    }

    /// The shard of a Slurm array task: `SLURM_ARRAY_TASK_ID` minus `SLURM_ARRAY_TASK_MIN`
    /// (0 when unset) out of `SLURM_ARRAY_TASK_COUNT`; `None` outside an array job.
    pub fn from_slurm(
        var: impl Fn(&str) -> Option<String>,
    ) -> std::result::Result<Option<Shard>, String> {
        let (Some(id), Some(count)) = (var("SLURM_ARRAY_TASK_ID"), var("SLURM_ARRAY_TASK_COUNT"))
        else {
            return Ok(None);
        };
        let number = |name: &str, text: &str| {
            text.trim()
                .parse::<usize>()
                .map_err(|_| format!("{name} = '{text}' is not a task number"))
        };
        let id = number("SLURM_ARRAY_TASK_ID", &id)?;
        let count = number("SLURM_ARRAY_TASK_COUNT", &count)?;
        let min = match var("SLURM_ARRAY_TASK_MIN") {
            Some(m) => number("SLURM_ARRAY_TASK_MIN", &m)?,
            None => 0,
        };
        match id.checked_sub(min).filter(|&i| i < count) {
            Some(index) => Ok(Some(Shard { index, count })),
            None => Err(format!(
                "SLURM_ARRAY_TASK_ID = {id} is not within SLURM_ARRAY_TASK_MIN = {min} + \
                 SLURM_ARRAY_TASK_COUNT = {count}: give the array as 0-{} (or use --shard)",
                count.saturating_sub(1)
            )),
        }
    }

    /// True when point `i` is this shard's.
    pub fn owns(&self, i: usize) -> bool {
        i % self.count == self.index
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index + 1, self.count)
    }
}

/// What this process does with the points of a sweep that are not stored yet.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Role {
    /// Compute every missing point (a plain run; it resumes an interrupted one).
    #[default]
    Whole,
    /// Compute this shard's missing points; stop at the first sweep that then still misses
    /// points of other shards.
    Shard(Shard),
    /// Compute nothing that is sharded: assemble from the point files, naming missing or
    /// failed points.
    Merge,
}

impl Role {
    /// The role from the command line (`--shard I/N`, `--merge`) or, without either, from a
    /// Slurm array task's environment.
    pub fn from_cli(
        shard: Option<&str>,
        merge: bool,
        var: impl Fn(&str) -> Option<String>,
    ) -> std::result::Result<Role, String> {
        match (shard, merge) {
            (Some(_), true) => Err("--shard and --merge exclude each other".into()),
            (Some(text), false) => Shard::parse(text).map(Role::Shard),
            (None, true) => Ok(Role::Merge),
            (None, false) => Ok(Shard::from_slurm(var)?.map_or(Role::Whole, Role::Shard)),
        }
    }
}

/// The key of a stored result: hex SHA-256 of the canonical JSON of (crate version, hash of
/// the sources the library was built from (see `build.rs`), kind, inputs): results of other
/// code are never reused. serde_json writes struct fields in declaration order, maps sorted (its default
/// `Map` is a BTreeMap) and floats in the shortest form that reads back to the same bits,
/// so equal inputs give equal keys in every process and on every machine.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Key(String);

impl Key {
    /// The key of `inputs` for a computation of `kind`; inputs holding a NaN or an infinity
    /// are refused (JSON writes both as `null`: +inf and -inf would share a key).
    pub fn of<I: Serialize + ?Sized>(kind: &str, inputs: &I) -> Result<Key> {
        refuse_non_finite(inputs)
            .map_err(|why| Error::Named(format!("cannot key a {kind} point: its input {why}")))?;
        let text = serde_json::to_vec(&(
            env!("CARGO_PKG_VERSION"),
            env!("TRNEWS_SOURCE_SHA256"),
            kind,
            inputs,
        ))
        .map_err(|e| Error::Named(format!("cannot key a {kind} point: {e}")))?;
        Ok(Key(hex(&Sha256::digest(&text))))
    }

    /// The key in hex.
    pub fn as_str(&self) -> &str {
        &self.0
    }
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// The stored record of one point.
#[derive(Serialize, Deserialize)]
struct PointFile {
    format: String,
    key: String,
    label: String,
    outcome: Outcome,
}

/// A finished point: its encoded value, or the error it failed with.
#[derive(Serialize, Deserialize)]
enum Outcome {
    Done(Vec<u8>),
    Failed(String),
}

/// What the store holds for a key.
enum Found {
    Done(Vec<u8>),
    Failed(String),
    Missing,
    Corrupt(String),
}

/// The most memory a stored value takes while it is decoded, per byte of its encoding. The
/// worst case is a `study::sweep` value: a `()` is 1 byte encoded, a 32-byte token, a
/// 32-byte plain value and a 16-byte script value. Typed results stay below 48 (an absent
/// `Option<Signal>` is 1 byte encoded and 40 in memory).
const DECODED_PER_ENCODED_BYTE: f64 = 96.0;

/// What a caller checks in a decoded value beyond its type: shapes and counts that its
/// computation guarantees (a trace per receiver, a focus per requested receiver). `Err` says
/// what is wrong.
pub type Expect<'a, T> = &'a dyn Fn(&T) -> std::result::Result<(), String>;

impl Found {
    /// A stored value is corrupt when decoding it could exceed the memory limit, when it does
    /// not decode as a `T` (signals are checked as they are decoded), when it holds a NaN, or
    /// when it fails `expect`: a checksum finds corruption, not a forged file.
    fn checked<T: Serialize + DeserializeOwned>(self, expect: Expect<T>) -> Found {
        let Found::Done(bytes) = self else {
            return self;
        };
        let decoded = bytes.len() as f64 * DECODED_PER_ENCODED_BYTE;
        let hint = "raise --max-memory to read it, or remove it to recompute it";
        let size = format!("{} bytes", bytes.len());
        if let Err(e) = crate::budget::check_memory("a point file", size, decoded, hint) {
            return Found::Corrupt(e.to_string());
        }
        let value = match decode::<T>(&bytes) {
            Ok(value) => value,
            Err(e) => return Found::Corrupt(format!("unreadable: {e}")),
        };
        match refuse_nan(&value).and_then(|()| expect(&value)) {
            Ok(()) => Found::Done(bytes),
            Err(why) => Found::Corrupt(format!("its value {why}")),
        }
    }
}

/// Text from a point file as it may be printed: control characters escaped (a forged file
/// cannot send terminal escape sequences), at most [`PRINTABLE_CHARS`] characters.
fn printable(text: &str) -> String {
    let mut out = String::new();
    for c in text.chars().take(PRINTABLE_CHARS) {
        if c.is_control() {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
    }
    if text.chars().nth(PRINTABLE_CHARS).is_some() {
        out.push_str("...");
    }
    out
}

/// The longest text from a point file that is printed whole.
const PRINTABLE_CHARS: usize = 2000;

/// Encodes a value with postcard (f64 as its 8 bytes).
pub fn encode<T: Serialize>(value: &T) -> Result<Vec<u8>> {
    postcard::to_stdvec(value).map_err(|e| Error::Named(format!("cannot encode a point: {e}")))
}

/// Decodes a value written by [`encode`].
pub fn decode<T: DeserializeOwned>(bytes: &[u8]) -> Result<T> {
    postcard::from_bytes(bytes).map_err(|e| Error::Named(format!("cannot decode a point: {e}")))
}

/// The point files of one output directory, and what this process does with them.
pub struct Store {
    dir: PathBuf,
    root: Option<OutputRoot>,
    role: Role,
    say: Box<dyn Fn(&str) + Send + Sync>,
}

impl fmt::Debug for Store {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Store")
            .field("dir", &self.dir)
            .field("role", &self.role)
            .finish()
    }
}

thread_local! {
    /// The store of the script running on this thread (see [`Store::within`]).
    static ACTIVE: RefCell<Option<Arc<Store>>> = const { RefCell::new(None) };
}

/// The store active on this thread, if any.
pub(crate) fn active_store() -> Option<Arc<Store>> {
    ACTIVE.with(|a| a.borrow().clone())
}

/// Runs `f` with `store` active on this thread, the previous one restored afterwards (also on
/// panic).
pub(crate) fn with_store<T>(store: Option<Arc<Store>>, f: impl FnOnce() -> T) -> T {
    struct Restore(Option<Arc<Store>>);
    impl Drop for Restore {
        fn drop(&mut self) {
            let old = self.0.take();
            ACTIVE.with(|a| *a.borrow_mut() = old);
        }
    }
    let old = ACTIVE.with(|a| std::mem::replace(&mut *a.borrow_mut(), store));
    let _restore = Restore(old);
    f()
}

/// Runs `f` with no store active: its first passes are computed and not stored (timing).
pub fn without_store<T>(f: impl FnOnce() -> T) -> T {
    with_store(None, f)
}

impl Store {
    /// The store under `out_dir` (files in `out_dir/points`), written through `root` when
    /// given, with `say` printing progress lines.
    pub fn new(
        out_dir: &Path,
        root: Option<OutputRoot>,
        role: Role,
        say: impl Fn(&str) + Send + Sync + 'static,
    ) -> Store {
        Store {
            dir: out_dir.join(POINTS_DIR),
            root,
            role,
            say: Box::new(say),
        }
    }

    /// What this process does with missing points.
    pub fn role(&self) -> Role {
        self.role
    }

    /// Runs `f` with this store active on the current thread (sweeps and first passes
    /// started by `f` use it); the previous one is restored afterwards, also on panic.
    pub fn within<T>(self: &Arc<Self>, f: impl FnOnce() -> T) -> T {
        with_store(Some(Arc::clone(self)), f)
    }

    fn path(&self, kind: &str, key: &Key) -> PathBuf {
        self.dir.join(kind).join(format!("{}.point", key.as_str()))
    }

    /// `path` relative to the output directory, for messages.
    fn shown(&self, kind: &str, key: &Key) -> String {
        format!("{POINTS_DIR}/{kind}/{}.point", key.as_str())
    }

    fn through_root<T>(&self, f: impl FnOnce() -> T) -> T {
        match &self.root {
            Some(root) => root.within(f),
            None => f(),
        }
    }

    /// What the file of `key` holds: checked against its checksum and key.
    fn load(&self, kind: &str, key: &Key) -> Found {
        let path = self.path(kind, key);
        let limit = crate::budget::memory_limit() / 2;
        let bytes = match self.through_root(|| crate::io::read_existing(&path, limit)) {
            Ok(Some(bytes)) => bytes,
            Ok(None) => return Found::Missing,
            Err(e) => return Found::Corrupt(e.to_string()),
        };
        let Some(split) = bytes.len().checked_sub(32) else {
            return Found::Corrupt(format!("{} bytes: truncated", bytes.len()));
        };
        let (body, sum) = bytes.split_at(split);
        if Sha256::digest(body).as_slice() != sum {
            return Found::Corrupt("checksum mismatch (truncated or corrupted)".into());
        }
        match postcard::from_bytes::<PointFile>(body) {
            Ok(file) if file.format != FORMAT => Found::Corrupt(format!(
                "format '{}', expected '{FORMAT}'",
                printable(&file.format)
            )),
            Ok(file) if file.key != key.as_str() => {
                Found::Corrupt(format!("holds key {}", printable(&file.key)))
            }
            Ok(file) => match file.outcome {
                Outcome::Done(value) => Found::Done(value),
                Outcome::Failed(error) => Found::Failed(printable(&error)),
            },
            Err(e) => Found::Corrupt(format!("unreadable: {e}")),
        }
    }

    /// Writes the point file of `key` whole.
    fn save(&self, kind: &str, key: &Key, label: &str, outcome: Outcome) -> Result<()> {
        let file = PointFile {
            format: FORMAT.into(),
            key: key.as_str().into(),
            label: label.into(),
            outcome,
        };
        let mut bytes = encode(&file)?;
        let sum = Sha256::digest(&bytes);
        bytes.extend_from_slice(&sum);
        let path = self.path(kind, key);
        self.through_root(|| crate::io::write_atomic(&path, &bytes))?;
        Ok(())
    }
}

/// Runs a shared first pass (an impulse response, the TR-NEWS chirp run and focusing)
/// through the active store: read back when stored under the key of (`kind`, `inputs`),
/// otherwise computed and stored. Without an active store (library use) it only computes.
/// In a merge nothing is computed: a missing first pass is an error naming its file. A stored
/// value failing `expect` is corrupt and recomputed.
pub fn first_pass<T, I>(
    kind: &str,
    label: &str,
    inputs: &I,
    expect: Expect<T>,
    compute: impl FnOnce() -> Result<T>,
) -> Result<T>
where
    T: Serialize + DeserializeOwned,
    I: Serialize + ?Sized,
{
    let Some(store) = active_store() else {
        return compute();
    };
    let key = Key::of(kind, inputs)?;
    match store.load(kind, &key).checked::<T>(expect) {
        Found::Done(bytes) => {
            (store.say)(&format!("{label}: read from {}", store.shown(kind, &key)));
            return decode(&bytes);
        }
        Found::Corrupt(why) => (store.say)(&format!(
            "{label}: {} is corrupt ({why}); recomputing",
            store.shown(kind, &key)
        )),
        Found::Failed(_) | Found::Missing => {}
    }
    if store.role == Role::Merge {
        return Err(Error::Named(format!(
            "merge: {label} is not stored ({}); run the sweep (or its shards) first, or run \
             without --merge to compute it here",
            store.shown(kind, &key)
        )));
    }
    let value = compute()?;
    refuse_nan(&value).map_err(|why| Error::Named(format!("{label}: the result {why}")))?;
    let bytes = encode(&value)?;
    store.save(kind, &key, label, Outcome::Done(bytes.clone()))?;
    decode(&bytes)
}

/// One point of a sweep as the store sees it.
#[derive(Clone, Debug)]
pub struct PointSpec {
    /// Key of everything that determines the point.
    pub key: Key,
    /// How the point is named in progress lines and messages, e.g. "tau = 1 us, a = 0.5".
    pub label: String,
    /// Whether the point is shared out among shards. Points that cost next to nothing
    /// (convolutions with a stored impulse response) are computed by whichever run needs
    /// them.
    pub sharded: bool,
}

/// Why a sweep did not return all its points.
#[derive(Debug)]
pub enum SweepError {
    /// A shard computed its share and the sweep still misses other shards' points: the
    /// run ends here, successfully.
    ShardDone(String),
    /// Points failed, or (in a merge) are missing: the message names them.
    Incomplete(String),
    /// Work stopped (time limit, Ctrl-C) or a point file could not be written.
    Stopped(Error),
}

impl fmt::Display for SweepError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SweepError::ShardDone(m) | SweepError::Incomplete(m) => write!(f, "{m}"),
            SweepError::Stopped(e) => write!(f, "{e}"),
        }
    }
}

impl From<Error> for SweepError {
    fn from(e: Error) -> Self {
        SweepError::Stopped(e)
    }
}

/// The state of one point during a sweep.
enum Slot {
    Done(Vec<u8>),
    Failed(String),
    Missing,
}

/// A sweep in progress: which points are stored, which this process computes
/// ([`Sweep::pending`]), and their outcomes as they finish ([`Sweep::record`], safe to call
/// from parallel workers).
pub struct Sweep {
    name: String,
    kind: String,
    store: Option<Arc<Store>>,
    points: Vec<PointSpec>,
    slots: Mutex<Vec<Slot>>,
    pending: Vec<usize>,
    stored: usize,
}

impl Sweep {
    /// Looks every point up in the active store (reporting corrupt files and values failing
    /// `expect`, which are recomputed) and decides which ones this process computes.
    pub fn start<T: Serialize + DeserializeOwned>(
        name: &str,
        kind: &str,
        points: Vec<PointSpec>,
        expect: Expect<T>,
    ) -> Sweep {
        let store = active_store();
        let role = store.as_ref().map_or(Role::Whole, |s| s.role);
        let mut slots = Vec::with_capacity(points.len());
        let mut pending = Vec::new();
        for (i, p) in points.iter().enumerate() {
            let found = store.as_ref().map_or(Found::Missing, |s| {
                s.load(kind, &p.key).checked::<T>(expect)
            });
            let slot = match found {
                Found::Done(bytes) => Slot::Done(bytes),
                Found::Failed(error) => Slot::Failed(error),
                Found::Missing => Slot::Missing,
                Found::Corrupt(why) => {
                    if let Some(s) = &store {
                        (s.say)(&format!(
                            "{name}: point {}/{} [{}]: {} is corrupt ({why}); recomputing",
                            i + 1,
                            points.len(),
                            p.label,
                            s.shown(kind, &p.key)
                        ));
                    }
                    Slot::Missing
                }
            };
            let computes = match role {
                Role::Whole => true,
                Role::Shard(shard) => !p.sharded || shard.owns(i),
                Role::Merge => !p.sharded,
            };
            if computes && !matches!(slot, Slot::Done(_)) {
                pending.push(i);
            }
            slots.push(slot);
        }
        let stored = slots.iter().filter(|s| matches!(s, Slot::Done(_))).count();
        Sweep {
            name: name.into(),
            kind: kind.into(),
            store,
            points,
            slots: Mutex::new(slots),
            pending,
            stored,
        }
    }

    /// The points this process computes, in order.
    pub fn pending(&self) -> &[usize] {
        &self.pending
    }

    fn say(&self, line: &str) {
        if let Some(s) = &self.store {
            (s.say)(line);
        }
    }

    /// Records the outcome of point `i`, computed in `seconds`, with `note` (its run report)
    /// in the progress line: stores it, or its error. A stopped computation (time limit,
    /// Ctrl-C) is not recorded and is returned, as is a failure to write the file.
    pub fn record<T: Serialize>(
        &self,
        i: usize,
        outcome: Result<T>,
        seconds: f64,
        note: &str,
    ) -> Result<()> {
        let p = &self.points[i];
        let head = format!(
            "{}: point {}/{} [{}]",
            self.name,
            i + 1,
            self.points.len(),
            p.label
        );
        let outcome = outcome.and_then(|value| {
            refuse_nan(&value)
                .map(|()| value)
                .map_err(|why| Error::Named(format!("the result {why}")))
        });
        let (slot, line, stored) = match outcome {
            Ok(value) => {
                let bytes = encode(&value)?;
                let line = format!("{head} done in {seconds:.2} s{note}");
                (Slot::Done(bytes.clone()), line, Outcome::Done(bytes))
            }
            Err(e @ Error::Stopped(_)) => return Err(e),
            Err(e) => {
                let message = e.to_string();
                let line = format!("{head} FAILED after {seconds:.2} s: {message}");
                (
                    Slot::Failed(message.clone()),
                    line,
                    Outcome::Failed(message),
                )
            }
        };
        if let Some(s) = &self.store {
            s.save(&self.kind, &p.key, &p.label, stored)?;
        }
        self.say(&line);
        if let Ok(mut slots) = self.slots.lock() {
            slots[i] = slot;
        }
        Ok(())
    }

    /// Every point's value, decoded from its stored bytes; or why not: other shards' points
    /// still missing (in a shard), failed points (named with their errors), missing points
    /// (in a merge).
    pub fn finish<T: DeserializeOwned>(self) -> std::result::Result<Vec<T>, SweepError> {
        let slots = self
            .slots
            .into_inner()
            .map_err(|_| Error::Named(format!("{}: a worker panicked", self.name)))?;
        let n = slots.len();
        let role = self.store.as_ref().map_or(Role::Whole, |s| s.role);
        let mut failed = Vec::new();
        let mut missing = Vec::new();
        for (i, slot) in slots.iter().enumerate() {
            let name = format!("{} [{}]", i + 1, self.points[i].label);
            match slot {
                Slot::Done(_) => {}
                Slot::Failed(e) => failed.push(format!("{name}: {e}")),
                Slot::Missing => missing.push(name),
            }
        }
        let computed = self.pending.len();
        let summary = format!(
            "{}: {n} points, {} stored before, {computed} computed here, {} failed, {} missing",
            self.name,
            self.stored,
            failed.len(),
            missing.len()
        );
        if let Some(s) = &self.store {
            (s.say)(&summary);
        }
        if failed.is_empty() && missing.is_empty() {
            return slots
                .into_iter()
                .map(|s| match s {
                    Slot::Done(bytes) => decode(&bytes).map_err(SweepError::from),
                    _ => unreachable!("every slot is done"),
                })
                .collect();
        }
        let dir = format!("{POINTS_DIR}/{}", self.kind);
        let failures = if failed.is_empty() {
            String::new()
        } else {
            format!("; failed points: {}", failed.join("; "))
        };
        match role {
            Role::Shard(shard) if failed.is_empty() => Err(SweepError::ShardDone(format!(
                "shard {shard}: {summary}; the missing points belong to other shards (their \
                 files go to {dir}); merge with --merge when every shard has finished"
            ))),
            Role::Merge => Err(SweepError::Incomplete(format!(
                "merge: {}: {} of {n} points are missing and {} failed, not plotting a \
                 partial sweep; missing points: {}{failures} (run their shards, or run \
                 without --merge to compute them here)",
                self.name,
                missing.len(),
                failed.len(),
                if missing.is_empty() {
                    "none".into()
                } else {
                    missing.join(", ")
                },
            ))),
            _ => Err(SweepError::Incomplete(format!(
                "{}: {} of {n} points failed (the others are stored under {dir}; a rerun \
                 computes only the failed ones){failures}",
                self.name,
                failed.len()
            ))),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_from_point_files_prints_without_control_characters() {
        assert_eq!(printable("a\u{1b}]0;x\u{7}\nb"), "a\\u{1b}]0;x\\u{7}\\nb");
        assert_eq!(
            printable(&"é".repeat(3000)).chars().count(),
            PRINTABLE_CHARS + 3
        );
    }

    #[test]
    fn shards_parse_one_based_and_share_points_round_robin() {
        let s = Shard::parse("2/3").unwrap();
        assert_eq!(s, Shard { index: 1, count: 3 });
        assert_eq!(s.to_string(), "2/3");
        assert_eq!(
            (0..7).filter(|&i| s.owns(i)).collect::<Vec<_>>(),
            vec![1, 4]
        );
        for bad in ["0/3", "4/3", "3", "a/b", "1/0", ""] {
            let e = Shard::parse(bad).unwrap_err();
            assert!(e.contains(&format!("--shard {bad}")), "{e}");
        }
    }

    #[test]
    fn slurm_array_tasks_become_shards() {
        let env = |pairs: &'static [(&'static str, &'static str)]| {
            move |name: &str| {
                pairs
                    .iter()
                    .find(|(n, _)| *n == name)
                    .map(|(_, v)| v.to_string())
            }
        };
        let task = env(&[
            ("SLURM_ARRAY_TASK_ID", "5"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
            ("SLURM_ARRAY_TASK_MIN", "3"),
        ]);
        assert_eq!(
            Role::from_cli(None, false, task).unwrap(),
            Role::Shard(Shard { index: 2, count: 4 })
        );
        assert_eq!(Role::from_cli(None, false, env(&[])).unwrap(), Role::Whole);
        let outside = env(&[
            ("SLURM_ARRAY_TASK_ID", "9"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
        ]);
        assert!(Role::from_cli(None, false, outside)
            .unwrap_err()
            .contains("SLURM_ARRAY_TASK_ID = 9"));
        // The command line wins over the environment; --merge excludes --shard.
        let task = env(&[
            ("SLURM_ARRAY_TASK_ID", "0"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
        ]);
        assert_eq!(Role::from_cli(None, true, task).unwrap(), Role::Merge);
        assert!(Role::from_cli(Some("1/2"), true, task).is_err());
    }

    #[test]
    fn keys_are_stable_and_values_round_trip_bit_exactly() {
        // Equal inputs give equal keys (other processes and later runs look files up by
        // them); the last bit of a float, or the kind, gives another.
        let k = Key::of("test", &(1.5f64, "a", [1u8, 2])).unwrap();
        assert_eq!(k, Key::of("test", &(1.5f64, "a", [1u8, 2])).unwrap());
        assert_ne!(
            k,
            Key::of("test", &(1.5000000000000002f64, "a", [1u8, 2])).unwrap()
        );
        assert_ne!(k, Key::of("other", &(1.5f64, "a", [1u8, 2])).unwrap());
        assert_eq!(k.as_str().len(), 64);
        // JSON writes +inf, -inf and NaN as null: such inputs are refused, never keyed alike.
        for v in [f64::INFINITY, f64::NEG_INFINITY, f64::NAN] {
            let e = Key::of("test", &[v]).unwrap_err().to_string();
            assert!(e.contains("cannot key a test point"), "{e}");
        }
        let values = vec![
            0.1f64,
            -0.0,
            f64::MIN_POSITIVE / 3.0,
            f64::INFINITY,
            f64::NAN,
            1e300,
        ];
        let back: Vec<f64> = decode(&encode(&values).unwrap()).unwrap();
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&back), bits(&values));
    }

    #[test]
    fn corrupt_and_truncated_point_files_are_found_and_recomputed() {
        let dir = std::env::temp_dir().join(format!("trnews-sweep-unit-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let lines = Arc::new(Mutex::new(Vec::<String>::new()));
        let sink = Arc::clone(&lines);
        let store = Arc::new(Store::new(&dir, None, Role::Whole, move |l| {
            sink.lock().unwrap().push(l.to_string())
        }));
        let points = |n: usize| {
            (0..n)
                .map(|i| PointSpec {
                    key: Key::of("unit", &i).unwrap(),
                    label: format!("p{i}"),
                    sharded: true,
                })
                .collect::<Vec<_>>()
        };
        let run = || {
            store.within(|| {
                let sweep = Sweep::start::<f64>("unit", "unit", points(3), &|_| Ok(()));
                let pending = sweep.pending().to_vec();
                for &i in &pending {
                    sweep.record(i, Ok(i as f64 * 0.1), 0.0, "").unwrap();
                }
                (pending, sweep.finish::<f64>().unwrap())
            })
        };
        let (first, values) = run();
        assert_eq!(first, vec![0, 1, 2]);
        assert_eq!(values, vec![0.0, 0.1, 0.2]);
        assert_eq!(run().0, Vec::<usize>::new(), "a rerun computes nothing");
        let file = |i: usize| store.path("unit", &Key::of("unit", &i).unwrap());
        let bytes = std::fs::read(file(0)).unwrap();
        std::fs::write(file(0), &bytes[..bytes.len() - 5]).unwrap();
        let mut flipped = std::fs::read(file(2)).unwrap();
        flipped[10] ^= 0x40;
        std::fs::write(file(2), flipped).unwrap();
        let (again, values) = run();
        assert_eq!(again, vec![0, 2]);
        assert_eq!(values, vec![0.0, 0.1, 0.2]);
        let said = lines.lock().unwrap().join("\n");
        assert!(
            said.contains("point 1/3 [p0]") && said.contains("is corrupt (checksum mismatch"),
            "{said}"
        );
        // A forged point (a NaN under a valid checksum) and a FIFO in place of a point file:
        // both refused, without blocking, and recomputed.
        let nan = Outcome::Done(encode(&f64::NAN).unwrap());
        store
            .save("unit", &Key::of("unit", &1).unwrap(), "p1", nan)
            .unwrap();
        std::fs::remove_file(file(2)).unwrap();
        let fifo = std::process::Command::new("mkfifo").arg(file(2)).status();
        let fifo = fifo.is_ok_and(|s| s.success());
        let (again, values) = run();
        assert_eq!(again, vec![1, 2]);
        assert_eq!(values, vec![0.0, 0.1, 0.2]);
        let said = lines.lock().unwrap().join("\n");
        assert!(said.contains("[p1]: points/unit/"), "{said}");
        assert!(
            said.contains("is corrupt (its value holds a NaN)"),
            "{said}"
        );
        if fifo {
            assert!(said.contains("not a regular file"), "{said}");
        }
        // A point file larger than half the memory limit is refused before it is read.
        crate::budget::set_memory_limit(64);
        let (again, _) = run();
        crate::budget::set_memory_limit(crate::budget::DEFAULT_MEMORY_LIMIT);
        assert_eq!(again, vec![0, 1, 2]);
        assert!(lines
            .lock()
            .unwrap()
            .join("\n")
            .contains("is larger than the 32.000 B"));
        // One small enough to read whose decoded value could exceed the limit (a forged
        // study::sweep value of unit tokens expands ~96x) is refused before decoding.
        let size = std::fs::metadata(file(0)).unwrap().len();
        crate::budget::set_memory_limit(4 * size);
        let (again, _) = run();
        crate::budget::set_memory_limit(crate::budget::DEFAULT_MEMORY_LIMIT);
        assert_eq!(again, vec![0, 1, 2]);
        let said = lines.lock().unwrap().join("\n");
        assert!(said.contains("a point file"), "{said}");
        // A value its caller cannot have computed (here: anything but 0.0) is recomputed.
        let only_zero = |v: &f64| {
            if *v == 0.0 {
                Ok(())
            } else {
                Err("is not 0".to_string())
            }
        };
        let pending = store.within(|| {
            Sweep::start::<f64>("unit", "unit", points(3), &only_zero)
                .pending()
                .to_vec()
        });
        assert_eq!(pending, vec![1, 2]);
        assert!(lines
            .lock()
            .unwrap()
            .join("\n")
            .contains("is corrupt (its value is not 0)"));
        // A result holding a NaN is recorded as a failure, never stored.
        store.within(|| {
            let sweep = Sweep::start::<f64>("nan", "nan", points(1), &|_| Ok(()));
            sweep.record(0, Ok(f64::NAN), 0.0, "").unwrap();
            let err = sweep.finish::<f64>().err().unwrap().to_string();
            assert!(err.contains("the result holds a NaN"), "{err}");
        });
        let _ = std::fs::remove_dir_all(&dir);
    }
}
