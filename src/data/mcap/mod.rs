//! MCAP recordings: a streaming linear reader (no summary or index needed, bounded memory)
//! decoding JSON, ROS 2 CDR and protobuf (Foxglove) marker messages, and a writer of JSON
//! marker frames.
//!
//! The files, in the order a read goes through them:
//! - `mod.rs`: the public constants, the entry points `read` and `read_from` (the walk over
//!   the file's records, then the samples checked and turned into series) and the reading
//!   state they share.
//! - `records.rs`: the limit on record lengths, the length checks before a record is parsed
//!   (each map entry charged to the budget), and one record read into the state.
//! - `chunks.rs`: the chunk pipeline: each chunk decompressed, CRC-checked and its JSON frames
//!   parsed ahead on the thread pool, then its records read in file order.
//! - `decode/`: which decoder a channel gets (the Foxglove JSON schemas that are not positions,
//!   the names given to unnamed points) and one message to samples; `json.rs` (the serde
//!   types and the canonical frame layout) and `protobuf.rs` (Foxglove messages); ROS 2 CDR
//!   is read by `data::ros_cdr`.
//! - `tf.rs`: the samples accumulated while reading, and `/tf` trees composed to their root.
//! - `write.rs`: the writer of JSON marker frames.
//! - `overlay.rs`: the writer of overlays for Foxglove (a recording and a model's motion).

mod chunks;
mod decode;
pub mod overlay;
mod records;
mod tf;
mod write;

pub use decode::{NOT_POSITIONS, POINTS_NAMES};
pub use overlay::FRAME_SCHEMA;
pub use records::record_limit;
pub use tf::TF_SAMPLE_LIMIT;
pub use write::write_json;

use super::{Budget, DataError, Parsed, ReadOptions, Series};
use ::mcap::records::op;
use ::mcap::sans_io::linear_reader::{LinearReadEvent, LinearReader, LinearReaderOptions};
use ::mcap::McapError;
use chunks::{ChunkBuffers, Deferred};
use decode::{Decoder, Failed, Reject};
use records::{plain, USED_RECORDS};
use std::collections::{BTreeMap, HashMap};
use std::io::Read;
use std::path::Path;
use tf::{compose_tf, Acc, Stamped};

/// Message encodings the reader decodes (channel encoding / schema).
pub const SUPPORTED: &str = "json (markers array per frame, or one point per topic), \
cdr with ros2msg schemas geometry_msgs/msg/PointStamped, PoseStamped, TransformStamped, \
tf2_msgs/msg/TFMessage, protobuf (schema a FileDescriptorSet) foxglove.FrameTransform, \
foxglove.PointsAnnotation; chunks uncompressed, zstd or lz4";

/// Read an MCAP file linearly (summary and index are not needed).
pub(crate) fn read(path: &Path, opts: &ReadOptions) -> Result<Parsed, DataError> {
    let file = std::fs::File::open(path).map_err(|source| DataError::Io {
        path: path.to_owned(),
        source,
    })?;
    let size = file
        .metadata()
        .ok()
        .filter(|m| m.is_file())
        .map(|m| m.len());
    // The reader asks for each record's header and body in turn: buffered, a small file is a
    // few reads instead of two system calls a record (94 for the shipped example).
    read_from(
        std::io::BufReader::with_capacity(1 << 16, file),
        path,
        opts,
        size,
    )
}

#[derive(Debug)]
enum ChannelState {
    Markers(Decoder),
    Ignored(String),
}

struct Channel {
    topic: String,
    state: ChannelState,
    decoded: usize,
}

/// What one record came to.
enum Step {
    /// Read on.
    Next,
    /// The file is damaged here (why); what was read before is kept.
    Damage(String),
    /// Past the time window: stop reading.
    Stop,
}

/// The decoding state of one read: channels, samples and counts, fed record by record.
struct Reading<'a> {
    path: &'a Path,
    opts: &'a ReadOptions,
    limit: usize,
    /// Schema records by id: name, encoding and data (protobuf's only).
    schemas: HashMap<u16, (String, String, Vec<u8>)>,
    /// The decoders made from each schema (by id and message encoding): a schema shared by
    /// many channels is decoded once.
    decoders: HashMap<(u16, String), Result<Decoder, Reject>>,
    channels: BTreeMap<u16, Channel>,
    /// The samples, and the file's budget (`acc.budget`).
    acc: Acc,
    parsed: Parsed,
    records: u64,
    messages: u64,
    unsupported_compression: Option<String>,
    window_end: Option<f64>,
    first_log_time: Option<u64>,
    stopped_at: Option<f64>,
    bufs: ChunkBuffers,
    /// The chunks taken, in preparation or prepared, not yet read, in file order.
    deferred: std::collections::VecDeque<Deferred>,
}

/// Read MCAP bytes from any reader, streaming; `path` labels errors; `size` (the file's
/// length, when known) bounds every length the file declares.
pub(crate) fn read_from(
    input: impl Read,
    path: &Path,
    opts: &ReadOptions,
    size: Option<u64>,
) -> Result<Parsed, DataError> {
    let limit = record_limit(size);
    // An unknown size (a stream) gets the largest limits.
    let budget = Budget::new(path, size.unwrap_or(u64::MAX));
    let mut st = Reading::new(path, opts, limit, budget);
    let (damage, bytes) = walk(input, &mut st, limit)?;
    finish(st, damage, bytes)
}

impl<'a> Reading<'a> {
    /// The state of a read of `path` before its first record: records up to `limit` bytes,
    /// what is decoded and kept charged to `budget`.
    fn new(path: &'a Path, opts: &'a ReadOptions, limit: usize, budget: Budget) -> Self {
        Reading {
            path,
            opts,
            limit,
            schemas: HashMap::new(),
            decoders: HashMap::new(),
            channels: BTreeMap::new(),
            acc: Acc::new(budget),
            parsed: Parsed::default(),
            records: 0,
            messages: 0,
            unsupported_compression: None,
            // With a time window, reading stops once marker messages are past its end (by
            // log_time, with a second of margin for stamps that differ from it): the rest is never
            // decoded.
            window_end: opts.time_window.map(|(_, end)| end + 1.0),
            first_log_time: None,
            stopped_at: None,
            bufs: ChunkBuffers::default(),
            deferred: Default::default(),
        }
    }
}

/// Where reading stopped on damage: why, and the file offset it is reported at when that is not
/// the bytes read (see `Reading::chunk`).
#[derive(Default)]
struct Damage {
    why: Option<String>,
    at: Option<u64>,
}

impl Damage {
    /// What a step came to: `false` to read on; `true` to stop, keeping the damage (and where it
    /// is reported).
    fn settle(&mut self, step: (Step, Option<u64>)) -> bool {
        match step {
            (Step::Next, _) => false,
            (Step::Damage(why), at) => {
                self.why = Some(why);
                self.at = at;
                true
            }
            (Step::Stop, _) => true,
        }
    }
}

/// Walk the file's records into `st` (records up to `limit` bytes) until its end, a stop or
/// damage; returns the damage and the bytes read (or the offset the damage is reported at).
fn walk(
    mut input: impl Read,
    st: &mut Reading,
    limit: usize,
) -> Result<(Option<String>, u64), DataError> {
    // Chunks come whole and are read here: decompressed in one call and walked with checked
    // lengths (the crate's record-by-record decompression is slower, and its walk through
    // uncompressed chunks can overflow).
    let mut reader = LinearReader::new_with_options(
        LinearReaderOptions::default()
            .with_record_length_limit(limit)
            .with_emit_chunks(true),
    );
    let mut bytes = 0u64;
    let mut damage = Damage::default();
    // The reader asks for exactly the bytes the next record needs, so the bytes read since
    // it last gave a record are the record in progress (after the magic, at first). They are
    // kept while that record is a chunk: when the file ends inside it, its records before the
    // cut are still read, as the crate's record-by-record reading did.
    let mut pending: Vec<u8> = Vec::new();
    let mut skip = ::mcap::MAGIC.len();
    let mut record_start = skip as u64;
    loop {
        let Some(event) = reader.next_event() else {
            // The end: the chunk taken last is read.
            damage.settle(st.flush()?);
            break;
        };
        let event = match event {
            Ok(e) => e,
            Err(e) => {
                let in_progress = pending.get(skip..).unwrap_or_default();
                read_error(
                    st,
                    e,
                    in_progress,
                    (record_start, bytes),
                    limit,
                    &mut damage,
                )?;
                break;
            }
        };
        match event {
            LinearReadEvent::ReadRequest(need) => {
                let buf = reader.insert(need);
                let n = input.read(buf).map_err(|source| DataError::Io {
                    path: st.path.to_owned(),
                    source,
                })?;
                if pending.get(skip).is_none_or(|&o| o == op::CHUNK) {
                    pending.extend_from_slice(&buf[..n]);
                }
                bytes += n as u64;
                reader.notify_read(n);
            }
            LinearReadEvent::Record { opcode, data } => {
                pending.clear();
                skip = 0;
                let start = std::mem::replace(&mut record_start, bytes);
                let step = if opcode == op::CHUNK {
                    st.chunk(data, data.len() as u64, start, bytes)?
                } else if let (Some(d), false) =
                    (st.deferred.back_mut(), USED_RECORDS.contains(&opcode))
                {
                    // Only counted: after the chunk taken before it is read.
                    d.counted.push((data.len(), bytes));
                    (Step::Next, None)
                } else {
                    // Records read come after the chunk taken before them.
                    match st.flush()? {
                        (Step::Next, _) => (st.record(opcode, data, None)?, None),
                        other => other,
                    }
                };
                if damage.settle(step) {
                    break;
                }
            }
        }
    }
    Ok((damage.why, damage.at.unwrap_or(bytes)))
}

/// The reader's error `e`: the chunk taken before is read first; a chunk the file ends inside
/// (its bytes so far `in_progress`, from `record_start`; `bytes` read) is read as far as it
/// goes; then the error is the damage, unless reading stopped before it.
fn read_error(
    st: &mut Reading,
    e: McapError,
    in_progress: &[u8],
    (record_start, bytes): (u64, u64),
    limit: usize,
    damage: &mut Damage,
) -> Result<(), DataError> {
    // The chunk taken before comes first.
    if damage.settle(st.flush()?) {
        return Ok(());
    }
    if let (McapError::UnexpectedEof, Some((&[op::CHUNK], rest))) =
        (&e, in_progress.split_first_chunk::<1>())
    {
        if let Some((len, body)) = rest.split_first_chunk::<8>() {
            let len = u64::from_le_bytes(*len);
            let taken = st.chunk(body, len, record_start, bytes)?;
            if damage.settle(taken) || damage.settle(st.flush()?) {
                return Ok(());
            }
        }
    }
    let why = match e {
        McapError::RecordTooLarge { opcode, len } => st.too_large(opcode, len),
        McapError::ChunkTooLarge(len) => format!(
            "chunk of {len} bytes: more than the {limit}-byte limit for a file of this size"
        ),
        other => plain(&other),
    };
    damage.settle((Step::Damage(why), None));
    Ok(())
}

/// After the walk: the checks on what was read (the topics asked for, the compression, the
/// damage), `/tf` composed, and the samples turned into series (or the error saying why there
/// are none).
fn finish(st: Reading, damage: Option<String>, bytes: u64) -> Result<Parsed, DataError> {
    let Reading {
        path,
        opts,
        channels,
        mut acc,
        mut parsed,
        records,
        messages,
        unsupported_compression,
        stopped_at,
        ..
    } = st;
    for t in &opts.topics {
        if !channels.values().any(|c| c.topic == *t) && damage.is_none() {
            return Err(DataError::Options {
                path: path.to_owned(),
                message: format!("--topic {t}: no such channel; {}", channel_list(&channels)),
            });
        }
    }
    if let Some(t) = stopped_at {
        parsed.notes.push(format!(
            "stopped reading at {t:.3} s: past the time window, the rest of the file is not decoded"
        ));
    }
    if let Some(c) = unsupported_compression {
        return Err(DataError::Unsupported {
            path: path.to_owned(),
            what: "chunk compression".into(),
            found: c,
            supported: "none, zstd, lz4".into(),
        });
    }
    if let Some(err) = damage {
        if acc.is_empty() {
            return Err(DataError::Mcap {
                path: path.to_owned(),
                at: format!("after {records} record(s), {bytes} byte(s)"),
                message: err,
            });
        }
        parsed.warnings.push(format!(
            "{}: damaged after {messages} message(s) ({records} records, {bytes} bytes read): {err}; \
             kept the frames before the damage",
            path.display()
        ));
    }
    let tf_notes = compose_tf(&mut acc, opts.plane).map_err(|e| match e {
        Failed::Budget(e) => e,
        Failed::Message(why) => {
            DataError::parse(path, "the /tf messages", "transforms", why, "more")
        }
    })?;
    parsed.notes.extend(tf_notes);
    if acc.series.is_empty() {
        return Err(no_markers(&channels, messages, path));
    }
    for c in channels.values() {
        if let ChannelState::Ignored(why) = &c.state {
            parsed
                .notes
                .push(format!("channel {} skipped: {why}", c.topic));
        }
    }
    marker_series(std::mem::take(&mut acc.series), &mut parsed, path)?;
    parsed.scale = Some((1.0, "metres (MCAP marker messages)".into()));
    parsed.notes.push(format!(
        "MCAP: {messages} message(s) on {} channel(s), read linearly; in-message stamps used where present",
        channels.len()
    ));
    Ok(parsed)
}

/// The channels for a message: each with its decoder or why it was skipped, sorted.
fn channel_list(channels: &BTreeMap<u16, Channel>) -> String {
    let mut v: Vec<String> = channels
        .values()
        .map(|c| match &c.state {
            ChannelState::Markers(d) => format!("{} ({d:?})", c.topic),
            ChannelState::Ignored(why) => format!("{} ({why})", c.topic),
        })
        .collect();
    v.sort();
    if v.is_empty() {
        "the file has no channels".into()
    } else {
        format!("channels {}", v.join("; "))
    }
}

/// Why a file gave no marker samples: its one channel's type is not supported, its channels
/// carry no messages, or none carries markers.
fn no_markers(channels: &BTreeMap<u16, Channel>, messages: u64, path: &Path) -> DataError {
    // Channels in id order, so the same file gives the same message on every run.
    let unsupported: Vec<&Channel> = channels
        .values()
        .filter(|c| matches!(&c.state, ChannelState::Ignored(w) if w.ends_with("not supported")))
        .collect();
    if unsupported.len() == 1 && channels.len() == 1 {
        let c = unsupported[0];
        let ChannelState::Ignored(why) = &c.state else {
            unreachable!()
        };
        return DataError::Unsupported {
            path: path.to_owned(),
            what: format!("channel {}", c.topic),
            found: why.trim_end_matches(" is not supported").to_string(),
            supported: SUPPORTED.into(),
        };
    }
    if messages == 0 && !channels.is_empty() {
        return DataError::NoFrames {
            path: path.to_owned(),
            what: channel_list(channels),
        };
    }
    DataError::NoMarkerChannel {
        path: path.to_owned(),
        channels: channel_list(channels),
        expected: SUPPORTED.into(),
    }
}

/// The samples per (channel, marker) into `parsed`'s series: a marker on several channels is
/// read from the first, times in seconds from the earliest stamp (also `parsed.time_base`); a
/// stamp repeated within a marker is an error.
fn marker_series(
    samples: Vec<(String, String, Stamped)>,
    parsed: &mut Parsed,
    path: &Path,
) -> Result<(), DataError> {
    // A marker on several channels (the same motion as points and as transforms): the first
    // channel it appeared on is read, the others are named in a note.
    let mut chosen: HashMap<String, String> = HashMap::new();
    let mut series = Vec::new();
    for (topic, name, s) in samples {
        match chosen.get(&name) {
            Some(first) => parsed.notes.push(format!(
                "marker {name:?} is also on channel {topic}: read from {first} (--topic to choose)"
            )),
            None => {
                chosen.insert(name.clone(), topic);
                series.push((name, s));
            }
        }
    }
    // Sort, check duplicates, convert to seconds from the earliest stamp (exact integer
    // differences first, in i128 so no pair of i64 stamps overflows).
    let mut t0 = i64::MAX;
    for (_, s) in &mut series {
        if !s.is_sorted_by_key(|x| x.0) {
            s.sort_by_key(|x| x.0);
        }
        t0 = t0.min(s[0].0);
    }
    let secs = |ns: i64| (ns as i128 - t0 as i128) as f64 / 1e9;
    for (name, s) in series {
        if let Some(w) = s.windows(2).find(|w| w[0].0 == w[1].0) {
            return Err(DataError::Time {
                path: path.to_owned(),
                at: format!("marker {name:?}"),
                time: secs(w[1].0),
                previous: secs(w[0].0),
                problem: "is repeated",
            });
        }
        parsed.series.push(Series {
            name,
            times: s.iter().map(|x| secs(x.0)).collect(),
            points: s.iter().map(|x| x.1).collect(),
        });
    }
    parsed.time_base = t0 as f64 / 1e9;
    parsed.time_base_ns = Some(t0);
    Ok(())
}
