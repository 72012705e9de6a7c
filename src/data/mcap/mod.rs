//! MCAP recordings: a streaming linear reader (no summary or index needed, bounded memory)
//! decoding JSON, ROS 2 CDR and protobuf (Foxglove) marker messages, and a writer of JSON
//! marker frames.

mod decode;
mod tf;
mod write;

pub use tf::TF_SAMPLE_LIMIT;
pub use write::{write_json, FRAME_SCHEMA};

use super::{DataError, Parsed, ReadOptions, Series};
use ::mcap::records::{op, MessageHeader, Metadata, Record};
use ::mcap::sans_io::linear_reader::{LinearReadEvent, LinearReader, LinearReaderOptions};
use ::mcap::McapError;
use decode::{decode, decoder_for, Decoder, PreFrame, PreParsed, Reject};
use std::collections::{BTreeMap, HashMap};
use std::io::Read;
use std::path::Path;
use tf::{compose_tf, Acc};

/// Message encodings the reader decodes (channel encoding / schema).
pub const SUPPORTED: &str = "json (markers array per frame, or one point per topic), \
cdr with ros2msg schemas geometry_msgs/msg/PointStamped, PoseStamped, TransformStamped, \
tf2_msgs/msg/TFMessage, protobuf (schema a FileDescriptorSet) foxglove.FrameTransform, \
foxglove.PointsAnnotation; chunks uncompressed, zstd or lz4";

/// JSON schemas (Foxglove's) whose x, y are not a position: skipped rather than read as
/// markers.
pub const NOT_POSITIONS: [&str; 6] = [
    "foxglove.Vector3",
    "foxglove.Vector2",
    "foxglove.Quaternion",
    "foxglove.LocationFix",
    "foxglove.Battery",
    "foxglove.Log",
];

/// Marker names given to the points of a `foxglove.PointsAnnotation`, which carries no names:
/// identity is the index (point 0 the slider, point 1 the bob, further points `point2`, ...).
pub const POINTS_NAMES: [&str; 2] = ["slider", "bob"];

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
    read_from(file, path, opts, size)
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

/// The largest record (or decompressed chunk record) read from a file of `size` bytes: 256
/// times the file (compressed chunks may hold records larger than the file), at least 1 MiB,
/// at most 256 MiB; 256 MiB when the size is unknown.
pub fn record_limit(size: Option<u64>) -> usize {
    const MIB: u64 = 1 << 20;
    let limit = size.map_or(256 * MIB, |s| s.saturating_mul(256).clamp(MIB, 256 * MIB));
    limit as usize
}

/// The most bytes the records of a file of `size` bytes may decompress to, in all: 1024 times
/// the file plus 64 MiB (a bomb of zeros stops here instead of running for minutes).
pub fn decompressed_limit(size: Option<u64>) -> u64 {
    size.unwrap_or(1 << 30)
        .saturating_mul(1024)
        .saturating_add(64 << 20)
}

/// Check that every length field of a Schema, Channel, Message or Metadata record fits in
/// the record, so parsing it allocates no more than the record holds.
fn check_lengths(opcode: u8, data: &[u8]) -> Result<(), String> {
    struct Cur<'a> {
        d: &'a [u8],
        at: usize,
    }
    impl Cur<'_> {
        fn skip(&mut self, n: usize, what: &str) -> Result<(), String> {
            match self.at.checked_add(n) {
                Some(end) if end <= self.d.len() => {
                    self.at = end;
                    Ok(())
                }
                _ => Err(format!(
                    "{what}: {n} byte(s) at offset {}, beyond the record's {} bytes",
                    self.at,
                    self.d.len()
                )),
            }
        }
        fn len(&mut self, what: &str) -> Result<usize, String> {
            let start = self.at;
            self.skip(4, what)?;
            let b: [u8; 4] = self.d[start..start + 4].try_into().expect("4 bytes");
            Ok(u32::from_le_bytes(b) as usize)
        }
        fn string(&mut self, what: &str) -> Result<(), String> {
            let n = self.len(what)?;
            self.skip(n, what)
        }
        fn map(&mut self, what: &str) -> Result<(), String> {
            let n = self.len(what)?;
            let end = self.at;
            self.skip(n, what)?;
            let mut inner = Cur {
                d: &self.d[end..end + n],
                at: 0,
            };
            while inner.at < n {
                inner.string(what)?;
                inner.string(what)?;
            }
            Ok(())
        }
    }
    let mut c = Cur { d: data, at: 0 };
    match opcode {
        op::SCHEMA => {
            c.skip(2, "schema id")?;
            c.string("schema name")?;
            c.string("schema encoding")?;
            c.string("schema data")
        }
        op::CHANNEL => {
            c.skip(4, "channel ids")?;
            c.string("topic")?;
            c.string("message encoding")?;
            c.map("channel metadata")
        }
        op::MESSAGE => c.skip(22, "message header"),
        op::METADATA => {
            c.string("metadata name")?;
            c.map("metadata")
        }
        _ => Ok(()),
    }
}

/// A Message record whose body (at least 22 bytes) is `data`: channel id, sequence, log time
/// and publish time (little-endian), then the payload, borrowed.
fn message_record(data: &[u8]) -> Record<'_> {
    let le = |at: usize, n: usize| {
        data[at..at + n]
            .iter()
            .rev()
            .fold(0u64, |v, &b| (v << 8) | u64::from(b))
    };
    Record::Message {
        header: MessageHeader {
            channel_id: le(0, 2) as u16,
            sequence: le(2, 4) as u32,
            log_time: le(6, 8),
            publish_time: le(14, 8),
        },
        data: std::borrow::Cow::Borrowed(&data[22..]),
    }
}

/// The first line of an mcap error, without terminal escape codes (binrw's errors carry a
/// coloured backtrace).
fn plain(err: &McapError) -> String {
    let text = err.to_string();
    let mut out = String::new();
    let mut chars = text.lines().next().unwrap_or("").chars().peekable();
    while let Some(c) = chars.next() {
        if c == '\u{1b}' {
            // CSI: ESC [ params final-byte
            if chars.peek() == Some(&'[') {
                chars.next();
                for d in chars.by_ref() {
                    if ('@'..='~').contains(&d) {
                        break;
                    }
                }
            }
        } else if !c.is_control() {
            out.push(c);
        }
    }
    out.trim().trim_end_matches(':').to_string()
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

/// The records read; the others are only counted.
const USED_RECORDS: [u8; 4] = [op::SCHEMA, op::CHANNEL, op::MESSAGE, op::METADATA];

/// The bytes of a chunk record before its records field: start and end time, uncompressed
/// size, CRC and compression length (8 + 8 + 8 + 4 + 4), the compression string, then the
/// compressed size (8).
const CHUNK_FIXED: usize = 32;

/// Buffers reused across chunks, so a file of many chunks allocates a few times only.
#[derive(Default)]
struct ChunkBuffers {
    spare: Vec<Vec<u8>>,
}

/// Chunks read while others are prepared on the thread pool.
const CHUNKS_AHEAD: usize = 3;

thread_local! {
    /// Each pool thread's zstd decoder, reused across chunks.
    static ZSTD: std::cell::RefCell<Option<::zstd::zstd_safe::DCtx<'static>>> =
        const { std::cell::RefCell::new(None) };
}

/// Decompress `src` (one chunk's compressed records) into `out`, at most `size` bytes, the way
/// the mcap crate's decoders do (frames after frames until `size` bytes; bytes past that are
/// ignored). Whatever came out before an error is kept in `out`; the error is returned.
fn decompress_chunk(
    compression: &str,
    src: &[u8],
    size: usize,
    zstd: &mut Option<::zstd::zstd_safe::DCtx<'static>>,
    out: &mut Vec<u8>,
) -> Option<String> {
    use ::zstd::zstd_safe::{get_error_name, DCtx, InBuffer, OutBuffer, ResetDirective};
    out.clear();
    // Only `size` bytes are asked for; the capacity bounds what the decoder may write.
    out.reserve_exact(size);
    let short = match compression {
        "zstd" => {
            let dctx = zstd.get_or_insert_with(DCtx::create);
            let mut input = InBuffer::around(src);
            let mut output = OutBuffer::around(out);
            let mut failed = None;
            while output.pos() < size && input.pos < src.len() {
                let before = (input.pos, output.pos());
                if let Err(code) = dctx.decompress_stream(&mut output, &mut input) {
                    failed = Some(McapError::DecompressionError(get_error_name(code).into()));
                    break;
                }
                if (input.pos, output.pos()) == before {
                    break;
                }
            }
            // A frame cut short or an error leaves the context mid-frame: the next chunk starts
            // clean.
            let _ = dctx.reset(ResetDirective::SessionOnly);
            failed
        }
        "lz4" => {
            let mut rest = src;
            let mut failed = None;
            // One lz4 decoder per frame: a chunk may hold several frames back to back.
            while out.len() < size && !rest.is_empty() {
                let before = (rest.len(), out.len());
                let read = ::lz4::Decoder::new(rest).and_then(|mut dec| {
                    let want = (size - out.len()) as u64;
                    let read = Read::by_ref(&mut dec).take(want).read_to_end(out);
                    rest = dec.finish().0;
                    read
                });
                if let Err(e) = read {
                    failed = Some(McapError::Io(e));
                    break;
                }
                if (rest.len(), out.len()) == before {
                    break;
                }
            }
            failed
        }
        _ => unreachable!("compression checked by the caller"),
    };
    out.truncate(size);
    short.map(|e| plain(&e))
}

/// Where the next record of a chunk ends, or why it cannot be read: `left` bytes of the
/// chunk's records remain (as declared), of which `avail` are at hand. Checked arithmetic
/// only: every length is compared with what remains, nothing is subtracted past zero.
enum NextRecord {
    /// The record's opcode and body length; its body follows the 9-byte opcode and length.
    Record(u8, usize),
    /// The 9-byte opcode and length, or the body, run past the chunk's end: the chunk is
    /// damaged.
    Beyond(String),
    /// The body is longer than the record limit.
    TooLarge(u8, u64),
    /// The bytes at hand end first (a truncated file or a decompression error).
    Short,
}

/// The record at the start of `rest` (`left` bytes of the chunk remain, `rest.len()` of them
/// at hand), checked against the chunk and the record `limit`.
fn next_in_chunk(rest: &[u8], left: u64, limit: usize) -> NextRecord {
    const HEAD: u64 = 9;
    if left < HEAD {
        return NextRecord::Beyond(format!(
            "its opcode and length: 9 bytes, beyond the {left} byte(s) left in the chunk"
        ));
    }
    let Some((&[opcode], tail)) = rest.split_first_chunk::<1>() else {
        return NextRecord::Short;
    };
    let Some(len) = tail.first_chunk::<8>().map(|b| u64::from_le_bytes(*b)) else {
        return NextRecord::Short;
    };
    // The limit first, as the mcap crate's reader checks it.
    let Some(body) = usize::try_from(len).ok().filter(|&n| n <= limit) else {
        return NextRecord::TooLarge(opcode, len);
    };
    let room = left - HEAD;
    if len > room {
        return NextRecord::Beyond(format!(
            "length {len} bytes, beyond the {room} byte(s) left in the chunk after its opcode and length"
        ));
    }
    if (rest.len() - 9) < body {
        return NextRecord::Short;
    }
    NextRecord::Record(opcode, body)
}

/// The decoding state of one read: channels, samples and counts, fed record by record.
struct Reading<'a> {
    path: &'a Path,
    opts: &'a ReadOptions,
    limit: usize,
    budget: u64,
    schemas: HashMap<u16, (String, String, Vec<u8>)>,
    channels: BTreeMap<u16, Channel>,
    acc: Acc,
    parsed: Parsed,
    records: u64,
    messages: u64,
    record_bytes: u64,
    unsupported_compression: Option<String>,
    window_end: Option<f64>,
    first_log_time: Option<u64>,
    stopped_at: Option<f64>,
    bufs: ChunkBuffers,
    /// The chunks taken, in preparation or prepared, not yet read, in file order.
    deferred: std::collections::VecDeque<Deferred>,
}

impl Reading<'_> {
    /// The damage text of a record longer than the limit.
    fn too_large(&self, opcode: u8, len: u64) -> String {
        format!(
            "record (opcode {opcode:#04x}) of {len} bytes: more than the {}-byte limit for a file of this size",
            self.limit
        )
    }

    /// Count a record of `len` bytes against the budget of decompressed bytes.
    fn tally(&mut self, len: usize) -> Option<Step> {
        self.records += 1;
        self.record_bytes += len as u64;
        (self.record_bytes > self.budget).then(|| {
            Step::Damage(format!(
                "records decompress to more than {} bytes (1024 times the file plus 64 MiB)",
                self.budget
            ))
        })
    }

    /// Read one record (outside chunks or inside one); `pre` is the message's canonical frame
    /// when it was parsed ahead.
    fn record(
        &mut self,
        opcode: u8,
        data: &[u8],
        pre: Option<PreFrame<'_>>,
    ) -> Result<Step, DataError> {
        let (path, opts) = (self.path, self.opts);
        if let Some(damage) = self.tally(data.len()) {
            return Ok(damage);
        }
        let records = self.records;
        // Only these records are used; the mcap crate sizes strings from their length
        // fields before checking them, so their lengths are checked here first.
        if !USED_RECORDS.contains(&opcode) {
            return Ok(Step::Next);
        }
        if let Err(why) = check_lengths(opcode, data) {
            return Ok(Step::Damage(format!(
                "record {records} (opcode {opcode:#04x}): {why}"
            )));
        }
        // A message's header is four fixed fields (check_lengths saw its 22 bytes):
        // read here, the payload borrowed, as parse_record would give them.
        let parsed_record = if opcode == op::MESSAGE {
            Ok(message_record(data))
        } else {
            ::mcap::parse_record(opcode, data)
        };
        let record = match parsed_record {
            Ok(r) => r,
            Err(e) => return Ok(Step::Damage(plain(&e))),
        };
        match record {
            Record::Schema { header, data } => {
                // Only protobuf needs the schema's bytes; keep memory bounded otherwise.
                let data = if header.encoding == "protobuf" {
                    data.into_owned()
                } else {
                    Vec::new()
                };
                self.schemas
                    .insert(header.id, (header.name, header.encoding, data));
            }
            Record::Channel(c) => {
                let (sname, senc, sdata) = self
                    .schemas
                    .get(&c.schema_id)
                    .map(|(n, e, d)| (n.as_str(), e.as_str(), d.as_slice()))
                    .unwrap_or_default();
                let state = if !opts.topics.is_empty() && !opts.topics.contains(&c.topic) {
                    ChannelState::Ignored("not chosen by --topic".into())
                } else {
                    match decoder_for(&c.message_encoding, sname, senc, sdata) {
                        Ok(d) => ChannelState::Markers(d),
                        Err(Reject::Unsupported(why)) => {
                            ChannelState::Ignored(format!("{why} is not supported"))
                        }
                        Err(Reject::Invalid(why)) => ChannelState::Ignored(why),
                    }
                };
                self.channels.entry(c.id).or_insert(Channel {
                    topic: c.topic,
                    state,
                    decoded: 0,
                });
            }
            Record::Message { header, data } => {
                self.messages += 1;
                let messages = self.messages;
                let Some(ch) = self.channels.get_mut(&header.channel_id) else {
                    return Err(DataError::parse(
                        path,
                        format!("record {records}"),
                        "channel id",
                        "a channel defined before its messages",
                        header.channel_id.to_string(),
                    ));
                };
                let ChannelState::Markers(dec) = &ch.state else {
                    return Ok(Step::Next);
                };
                if let Some(end) = self.window_end {
                    let first = *self.first_log_time.get_or_insert(header.log_time);
                    let since = header.log_time.saturating_sub(first) as f64 * 1e-9;
                    if since > end {
                        self.stopped_at = Some(since);
                        return Ok(Step::Stop);
                    }
                }
                let result = match i64::try_from(header.log_time) {
                    Ok(log_time) => decode(
                        dec,
                        &ch.topic,
                        &data,
                        log_time,
                        opts.plane,
                        &mut self.acc,
                        pre,
                    ),
                    Err(_) => Err(format!(
                        "a log_time below 2^63 ns (year 2262), found {}",
                        header.log_time
                    )),
                };
                match result {
                    Ok(_) => ch.decoded += 1,
                    Err(why) if ch.decoded == 0 => {
                        ch.state = ChannelState::Ignored(format!(
                            "its first message is not marker data: {why}"
                        ));
                    }
                    Err(why) => {
                        return Err(DataError::parse(
                            path,
                            format!("message {messages} (record {records}) on {}", ch.topic),
                            "message",
                            "marker data like the channel's earlier messages",
                            why,
                        ))
                    }
                }
            }
            Record::Metadata(Metadata { name, metadata }) => {
                for (k, v) in metadata {
                    self.parsed.metadata.insert(format!("{name}.{k}"), v);
                }
            }
            _ => {}
        }
        Ok(Step::Next)
    }

    /// Take a chunk record's `body` (everything after its opcode and length `len`; fewer bytes
    /// than `len` when the file ends inside it; `start` is its offset in the file, `bytes` the
    /// bytes read so far). It is prepared ([`prepare_chunk`]: header, decompression, CRC,
    /// canonical frames) on the thread pool while the reader reads on, and read in order once
    /// [`CHUNKS_AHEAD`] chunks are taken after it, or by [`Reading::flush`]. Returns what
    /// reading the chunk that came due came to: the step, and the file offset the damage is
    /// reported at.
    fn chunk(
        &mut self,
        body: &[u8],
        len: u64,
        start: u64,
        bytes: u64,
    ) -> Result<(Step, Option<u64>), DataError> {
        // The budget left before the chunks ahead are read: looser than when this chunk is
        // read (checked again then), so at most CHUNKS_AHEAD + 1 budgets are held at once.
        let room = self.budget.saturating_sub(self.record_bytes);
        let (budget, limit) = (self.budget, self.limit);
        let out = self.bufs.spare.pop().unwrap_or_default();
        // The reader's buffer moves on: the chunk is copied for the pool.
        let body = body.to_vec();
        let (tx, ready) = std::sync::mpsc::sync_channel(1);
        let prepare = move || {
            let prepared = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                let mut zstd = ZSTD.take();
                let prepared =
                    prepare_chunk(&body, len, start, (room, budget, limit), &mut zstd, out);
                ZSTD.set(zstd);
                prepared
            }))
            .unwrap_or_else(|_| Prepared::Damage(format!("chunk at byte {start}: unreadable")));
            // The receiver is gone only when reading stopped before this chunk.
            let _ = tx.send(prepared);
        };
        // On a pool thread (a directory's recordings are read in parallel) the chunk is
        // prepared here: waiting there for the pool could leave no thread to prepare it.
        if rayon::current_thread_index().is_some() {
            prepare();
        } else {
            rayon::spawn(prepare);
        }
        self.deferred.push_back(Deferred {
            ready,
            start,
            bytes,
            counted: Vec::new(),
        });
        if self.deferred.len() > CHUNKS_AHEAD {
            let due = self.deferred.pop_front().expect("more than CHUNKS_AHEAD");
            return self.finish_chunk(due);
        }
        Ok((Step::Next, None))
    }

    /// Read the chunks taken and not yet read, in order (before any record that is read, and
    /// at the end); those after a chunk that stops the reading are dropped.
    fn flush(&mut self) -> Result<(Step, Option<u64>), DataError> {
        while let Some(d) = self.deferred.pop_front() {
            let read = self.finish_chunk(d)?;
            if !matches!(read.0, Step::Next) {
                self.deferred.clear();
                return Ok(read);
            }
        }
        Ok((Step::Next, None))
    }

    /// Read a prepared chunk's records in order. Damage is reported at the bytes read when
    /// the chunk was (the reader has read on since), unless a place in the file is known.
    fn finish_chunk(&mut self, d: Deferred) -> Result<(Step, Option<u64>), DataError> {
        let prepared = d
            .ready
            .recv()
            .unwrap_or_else(|_| Prepared::Damage(format!("chunk at byte {}: unreadable", d.start)));
        let (step, at) = match prepared {
            Prepared::Damage(why) => (Step::Damage(why), None),
            Prepared::Unsupported(c) => {
                let why = plain(&McapError::UnsupportedCompression(c.clone()));
                self.unsupported_compression = Some(c);
                (Step::Damage(why), None)
            }
            Prepared::Records(r) => {
                let room = self.budget.saturating_sub(self.record_bytes);
                let result = match r.uncompressed {
                    Some(size) if size > room => {
                        Ok((Step::Damage(over_budget(self.budget, d.start, size)), None))
                    }
                    _ => self.chunk_records(&r, d.start),
                };
                self.bufs.spare.push(r.out);
                result?
            }
        };
        if let Step::Damage(_) = step {
            return Ok((step, at.or(Some(d.bytes))));
        }
        if let Step::Next = step {
            for (len, bytes) in d.counted {
                if let Some(damage) = self.tally(len) {
                    return Ok((damage, Some(bytes)));
                }
            }
        }
        Ok((step, at))
    }

    /// Check the CRC of a chunk's records (all of them when none are short) and read them.
    fn chunk_records(
        &mut self,
        r: &ChunkRecords,
        start: u64,
    ) -> Result<(Step, Option<u64>), DataError> {
        let (records, declared, in_file) = (&r.out[..], r.declared, r.in_file);
        if let Some(calculated) = r.calculated_crc.filter(|&c| c != r.crc) {
            let err = McapError::BadChunkCrc {
                saved: r.crc,
                calculated,
            };
            return Ok((
                Step::Damage(format!("chunk at byte {start}: {}", plain(&err))),
                None,
            ));
        }
        let mut at = 0usize;
        // Message records read so far: the index of the next one's frame parsed ahead.
        let mut message = 0usize;
        loop {
            // at <= records.len() <= declared throughout.
            let left = declared - at as u64;
            if left == 0 {
                return Ok((Step::Next, None));
            }
            let rest = &records[at..];
            // Where the record's opcode and length end in the file (uncompressed chunks).
            let head_end = in_file.map(|f| f + at as u64 + 9);
            match next_in_chunk(rest, left, self.limit) {
                NextRecord::Record(opcode, len) => {
                    let data = &rest[9..9 + len];
                    at += 9 + len;
                    let pre = if opcode == op::MESSAGE {
                        message += 1;
                        r.pre.frame(message - 1)
                    } else {
                        None
                    };
                    let step = self.record(opcode, data, pre)?;
                    if !matches!(step, Step::Next) {
                        return Ok((step, in_file.map(|f| f + at as u64)));
                    }
                }
                NextRecord::TooLarge(opcode, len) => {
                    return Ok((Step::Damage(self.too_large(opcode, len)), head_end));
                }
                NextRecord::Beyond(why) => {
                    let n = self.records + 1;
                    return Ok((
                        Step::Damage(format!("record {n} (in the chunk at byte {start}): {why}")),
                        head_end.filter(|_| rest.len() >= 9),
                    ));
                }
                NextRecord::Short => {
                    let why = r
                        .short
                        .clone()
                        .unwrap_or_else(|| plain(&McapError::UnexpectedEoc));
                    return Ok((Step::Damage(why), None));
                }
            }
        }
    }
}

/// The damage text of a chunk at `start` declaring `size` decompressed bytes, past `budget`.
fn over_budget(budget: u64, start: u64, size: u64) -> String {
    format!(
        "records decompress to more than {budget} bytes (1024 times the file plus 64 MiB): the chunk at byte {start} declares {size}"
    )
}

/// A chunk taken by [`Reading::chunk`], waiting to be read in order.
struct Deferred {
    /// Where the pool sends the chunk prepared.
    ready: std::sync::mpsc::Receiver<Prepared>,
    /// The chunk's offset in the file.
    start: u64,
    /// The bytes read when the chunk was taken.
    bytes: u64,
    /// Records after it that are only counted (message indexes follow every chunk): their
    /// lengths and the bytes read when each was, counted once the chunk is read, so the
    /// chunk is read beside the next one.
    counted: Vec<(usize, u64)>,
}

/// A chunk made ready to read by [`prepare_chunk`].
enum Prepared {
    /// Damaged before its records (why).
    Damage(String),
    /// Its compression is not supported (the name).
    Unsupported(String),
    /// Its records.
    Records(ChunkRecords),
}

/// A chunk's records, decompressed (or copied, when stored uncompressed), as far as they
/// could be had.
struct ChunkRecords {
    out: Vec<u8>,
    /// The records' length as the chunk declares it.
    declared: u64,
    /// A compressed chunk's declared uncompressed size, checked against the budget again when
    /// the chunk is read.
    uncompressed: Option<u64>,
    /// The CRC the chunk declares (0: none).
    crc: u32,
    /// The CRC of the records, computed when all are at hand and one is declared.
    calculated_crc: Option<u32>,
    /// Why fewer bytes than declared are at hand.
    short: Option<String>,
    /// Where the records lie in the file (uncompressed chunks).
    in_file: Option<u64>,
    /// The message records' canonical frames, parsed ahead.
    pre: PreParsed,
}

/// Prepare a chunk record's `body` (see [`Reading::chunk`]): check its header, decompress its
/// records in one go into `out` (at most `room` bytes of the `budget`), compute their CRC and
/// parse the canonical JSON frames of its messages (records longer than `limit` are left to
/// the ordered read, which reports them). Touches no reading state, so it runs beside the
/// ordered read of the chunk before.
fn prepare_chunk(
    body: &[u8],
    len: u64,
    start: u64,
    (room, budget, limit): (u64, u64, usize),
    zstd: &mut Option<::zstd::zstd_safe::DCtx<'static>>,
    mut out: Vec<u8>,
) -> Prepared {
    let complete = body.len() as u64 == len;
    let eof = || plain(&McapError::UnexpectedEof);
    let at_chunk = |why: String| format!("chunk at byte {start}: {why}");
    // The fixed fields and the compression string's length.
    let Some(cl) = body.get(CHUNK_FIXED - 4..CHUNK_FIXED) else {
        return Prepared::Damage(if complete {
            at_chunk(plain(&McapError::BadChunkLength {
                header: (CHUNK_FIXED + 8) as u64,
                available: len,
            }))
        } else {
            eof()
        });
    };
    let cl = u32::from_le_bytes(cl.try_into().expect("4 bytes"));
    let header_len = (CHUNK_FIXED as u64 + 8).saturating_add(u64::from(cl));
    if header_len > len {
        return Prepared::Damage(plain(&McapError::BadChunkLength {
            header: header_len,
            available: len,
        }));
    }
    // header_len <= len, which the reader held in memory: it fits in usize.
    let header_len = header_len as usize;
    let Some(header) = body.get(..header_len) else {
        return Prepared::Damage(eof());
    };
    let le64 = |at: usize| u64::from_le_bytes(header[at..at + 8].try_into().expect("8 bytes"));
    let uncompressed_size = le64(16);
    let crc = u32::from_le_bytes(header[24..28].try_into().expect("4 bytes"));
    let compressed_size = le64(header_len - 8);
    let Ok(compression) = std::str::from_utf8(&header[CHUNK_FIXED..header_len - 8]) else {
        return Prepared::Damage(at_chunk("compression: not UTF-8".into()));
    };
    if compressed_size > len - header_len as u64 {
        return Prepared::Damage(at_chunk(format!(
            "compressed size {compressed_size} bytes, beyond the record's {} byte(s) after the chunk header",
            len - header_len as u64
        )));
    }
    let src = &body[header_len..body.len().min(header_len + compressed_size as usize)];
    let (declared, short, in_file, uncompressed) = match compression {
        // Records of an uncompressed chunk lie in the file from here; copied, as the reader's
        // buffer moves on before they are read.
        "" => {
            out.clear();
            out.extend_from_slice(src);
            (
                compressed_size,
                (!complete).then(eof),
                Some(start + 9 + header_len as u64),
                None,
            )
        }
        "zstd" | "lz4" => {
            // Checked before allocating: the declared size is untrusted.
            let size = match usize::try_from(uncompressed_size) {
                Ok(size) if uncompressed_size <= room => size,
                _ => {
                    return Prepared::Damage(over_budget(budget, start, uncompressed_size));
                }
            };
            let failed = decompress_chunk(compression, src, size, zstd, &mut out);
            // Fewer bytes than declared: the file ended inside the chunk, or its data is bad.
            let short = (out.len() < size).then(|| match failed {
                _ if !complete => eof(),
                Some(why) => why,
                None => plain(&McapError::DecompressionError(
                    "decompressor made no progress".into(),
                )),
            });
            (uncompressed_size, short, None, Some(uncompressed_size))
        }
        other => return Prepared::Unsupported(other.to_string()),
    };
    // A CRC of 0 means none was written; a partial chunk has nothing to check it against.
    let calculated_crc = (crc != 0 && short.is_none()).then(|| crc32fast::hash(&out));
    // The message records, walked as the ordered read walks them, up to where it would stop.
    let mut messages = Vec::new();
    let mut at = 0usize;
    while let NextRecord::Record(opcode, n) = next_in_chunk(&out[at..], declared - at as u64, limit)
    {
        if opcode == op::MESSAGE {
            messages.push(&out[at + 9..at + 9 + n]);
        }
        at += 9 + n;
        if at as u64 == declared {
            break;
        }
    }
    let pre = PreParsed::parse(&messages);
    Prepared::Records(ChunkRecords {
        declared,
        uncompressed,
        crc,
        calculated_crc,
        short,
        in_file,
        pre,
        out,
    })
}

/// Read MCAP bytes from any reader, streaming; `path` labels errors; `size` (the file's
/// length, when known) bounds every length the file declares.
pub(crate) fn read_from(
    mut input: impl Read,
    path: &Path,
    opts: &ReadOptions,
    size: Option<u64>,
) -> Result<Parsed, DataError> {
    let limit = record_limit(size);
    let budget = decompressed_limit(size);
    // Chunks come whole and are read here: decompressed in one call and walked with checked
    // lengths (the crate's record-by-record decompression is slower, and its walk through
    // uncompressed chunks can overflow).
    let mut reader = LinearReader::new_with_options(
        LinearReaderOptions::default()
            .with_record_length_limit(limit)
            .with_emit_chunks(true),
    );
    let mut st = Reading {
        path,
        opts,
        limit,
        budget,
        schemas: HashMap::new(),
        channels: BTreeMap::new(),
        acc: Acc::default(),
        parsed: Parsed::default(),
        records: 0,
        messages: 0,
        record_bytes: 0,
        unsupported_compression: None,
        // With a time window, reading stops once marker messages are past its end (by
        // log_time, with a second of margin for stamps that differ from it): the rest is never
        // decoded.
        window_end: opts.time_window.map(|(_, end)| end + 1.0),
        first_log_time: None,
        stopped_at: None,
        bufs: ChunkBuffers::default(),
        deferred: Default::default(),
    };
    let mut bytes = 0u64;
    let mut damage: Option<String> = None;
    // Where the damage is reported when not at `bytes` (see `Reading::chunk`).
    let mut damage_at: Option<u64> = None;
    // The reader asks for exactly the bytes the next record needs, so the bytes read since
    // it last gave a record are the record in progress (after the magic, at first). They are
    // kept while that record is a chunk: when the file ends inside it, its records before the
    // cut are still read, as the crate's record-by-record reading did.
    let mut pending: Vec<u8> = Vec::new();
    let mut skip = ::mcap::MAGIC.len();
    let mut record_start = skip as u64;
    // What a step came to: read on, or stop with the damage (and where it is reported).
    let mut settle = |step: (Step, Option<u64>)| match step {
        (Step::Next, _) => false,
        (Step::Damage(why), at) => {
            damage = Some(why);
            damage_at = at;
            true
        }
        (Step::Stop, _) => true,
    };
    loop {
        let Some(event) = reader.next_event() else {
            // The end: the chunk taken last is read.
            settle(st.flush()?);
            break;
        };
        let event = match event {
            Ok(e) => e,
            Err(e) => {
                // The chunk taken before comes first.
                if settle(st.flush()?) {
                    break;
                }
                let in_progress = pending.get(skip..).unwrap_or_default();
                if let (McapError::UnexpectedEof, Some((&[op::CHUNK], rest))) =
                    (&e, in_progress.split_first_chunk::<1>())
                {
                    if let Some((len, body)) = rest.split_first_chunk::<8>() {
                        let len = u64::from_le_bytes(*len);
                        let taken = st.chunk(body, len, record_start, bytes)?;
                        if settle(taken) || settle(st.flush()?) {
                            break;
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
                settle((Step::Damage(why), None));
                break;
            }
        };
        match event {
            LinearReadEvent::ReadRequest(need) => {
                let buf = reader.insert(need);
                let n = input.read(buf).map_err(|source| DataError::Io {
                    path: path.to_owned(),
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
                if settle(step) {
                    break;
                }
            }
        }
    }
    let bytes = damage_at.unwrap_or(bytes);
    let Reading {
        channels,
        mut acc,
        mut parsed,
        records,
        messages,
        unsupported_compression,
        stopped_at,
        ..
    } = st;
    let channel_list = || {
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
    };
    for t in &opts.topics {
        if !channels.values().any(|c| c.topic == *t) && damage.is_none() {
            return Err(DataError::Options {
                path: path.to_owned(),
                message: format!("--topic {t}: no such channel; {}", channel_list()),
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
    let tf_notes = compose_tf(&mut acc, opts.plane)
        .map_err(|why| DataError::parse(path, "the /tf messages", "transforms", why, "more"))?;
    parsed.notes.extend(tf_notes);
    if acc.series.is_empty() {
        // Channels in id order, so the same file gives the same message on every run.
        let unsupported: Vec<&Channel> = channels
            .values()
            .filter(
                |c| matches!(&c.state, ChannelState::Ignored(w) if w.ends_with("not supported")),
            )
            .collect();
        if unsupported.len() == 1 && channels.len() == 1 {
            let c = unsupported[0];
            let ChannelState::Ignored(why) = &c.state else {
                unreachable!()
            };
            return Err(DataError::Unsupported {
                path: path.to_owned(),
                what: format!("channel {}", c.topic),
                found: why.trim_end_matches(" is not supported").to_string(),
                supported: SUPPORTED.into(),
            });
        }
        if messages == 0 && !channels.is_empty() {
            return Err(DataError::NoFrames {
                path: path.to_owned(),
                what: channel_list(),
            });
        }
        return Err(DataError::NoMarkerChannel {
            path: path.to_owned(),
            channels: channel_list(),
            expected: SUPPORTED.into(),
        });
    }
    for c in channels.values() {
        if let ChannelState::Ignored(why) = &c.state {
            parsed
                .notes
                .push(format!("channel {} skipped: {why}", c.topic));
        }
    }
    // A marker on several channels (the same motion as points and as transforms): the first
    // channel it appeared on is read, the others are named in a note.
    let mut chosen: HashMap<String, String> = HashMap::new();
    let mut series = Vec::new();
    for (topic, name, s) in std::mem::take(&mut acc.series) {
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
    parsed.scale = Some((1.0, "metres (MCAP marker messages)".into()));
    parsed.notes.push(format!(
        "MCAP: {messages} message(s) on {} channel(s), read linearly; in-message stamps used where present",
        channels.len()
    ));
    Ok(parsed)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::Recording;
    use rand::{Rng, SeedableRng};

    /// A recording of `frames` frames at 10 kHz, both markers moving, as MCAP bytes.
    fn multi_chunk_mcap(frames: usize) -> (Vec<u8>, Recording) {
        let mut rec = Recording::default();
        for k in 0..frames {
            let t = k as f64 * 1e-4;
            rec.times.push(t);
            rec.slider.push(Some([0.01 * (3.0 * t).sin(), 0.0]));
            rec.bob.push(Some([0.3 * t.cos(), -0.3 * t.sin()]));
        }
        let mut bytes = Vec::new();
        write_json(
            &mut bytes,
            &rec,
            1_700_000_000_000_000_000,
            &BTreeMap::new(),
        )
        .unwrap();
        (bytes, rec)
    }

    #[test]
    fn chunks_read_on_a_pool_thread_do_not_wait_for_the_pool() {
        // 60,000 frames: tens of chunks, more than are prepared ahead.
        let (bytes, rec) = multi_chunk_mcap(60_000);
        // Top-level records: opcode, length, body; chunks counted until the footer.
        let (mut at, mut chunks) = (::mcap::MAGIC.len(), 0);
        while bytes[at] != op::FOOTER {
            chunks += usize::from(bytes[at] == op::CHUNK);
            at += 9 + u64::from_le_bytes(bytes[at + 1..at + 9].try_into().unwrap()) as usize;
        }
        assert!(chunks > CHUNKS_AHEAD, "{chunks}");
        let read = |bytes: &[u8]| {
            read_from(bytes, Path::new("t.mcap"), &ReadOptions::default(), None).unwrap()
        };
        let outside = read(&bytes);
        // A pool of one thread, busy reading: its chunks cannot be handed to it.
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let inside = pool.install(|| read(&bytes));
        for parsed in [&outside, &inside] {
            assert_eq!(parsed.series.len(), 2);
            for s in &parsed.series {
                assert_eq!(s.times.len(), rec.times.len());
                let truth = if s.name == "slider" {
                    &rec.slider
                } else {
                    &rec.bob
                };
                assert_eq!(&s.points, truth, "{}", s.name);
            }
        }
    }

    #[test]
    fn message_headers_read_as_parse_record_reads_them() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        for _ in 0..100 {
            let mut body: Vec<u8> = (0..22).map(|_| rng.random()).collect();
            body.extend_from_slice(b"{\"x\":1}");
            let Record::Message { header, data } =
                ::mcap::parse_record(op::MESSAGE, &body).unwrap()
            else {
                panic!("a message");
            };
            let Record::Message { header: h, data: d } = message_record(&body) else {
                panic!("a message");
            };
            assert_eq!(
                (h.channel_id, h.sequence, h.log_time, h.publish_time),
                (
                    header.channel_id,
                    header.sequence,
                    header.log_time,
                    header.publish_time
                )
            );
            assert_eq!(d, data);
        }
    }

    /// A record of `opcode` with `body`, as MCAP frames it.
    fn framed(opcode: u8, body: &[u8]) -> Vec<u8> {
        let mut v = vec![opcode];
        v.extend_from_slice(&(body.len() as u64).to_le_bytes());
        v.extend_from_slice(body);
        v
    }

    /// An uncompressed chunk record holding `records` (CRC 0: none written).
    fn uncompressed_chunk(records: &[u8]) -> Vec<u8> {
        let mut body = Vec::new();
        body.extend_from_slice(&0u64.to_le_bytes()); // start time
        body.extend_from_slice(&0u64.to_le_bytes()); // end time
        body.extend_from_slice(&(records.len() as u64).to_le_bytes());
        body.extend_from_slice(&0u32.to_le_bytes()); // CRC
        body.extend_from_slice(&0u32.to_le_bytes()); // compression ""
        body.extend_from_slice(&(records.len() as u64).to_le_bytes());
        body.extend_from_slice(records);
        framed(op::CHUNK, &body)
    }

    #[test]
    fn chunk_walk_rejects_lengths_past_the_chunk_without_wrapping() {
        // A record claiming 100 bytes with 10 left after its opcode and length.
        let mut rest = framed(op::MESSAGE, &[0; 10]);
        rest[1..9].copy_from_slice(&100u64.to_le_bytes());
        assert!(matches!(
            next_in_chunk(&rest, rest.len() as u64, 1 << 20),
            NextRecord::Beyond(why) if why.contains("length 100 bytes, beyond the 10 byte(s)")
        ));
        // Fewer than 9 bytes left in the chunk: no room for an opcode and length.
        assert!(matches!(
            next_in_chunk(&rest, 5, 1 << 20),
            NextRecord::Beyond(why) if why.contains("beyond the 5 byte(s)")
        ));
        // The largest length: the limit catches it first, nothing overflows.
        rest[1..9].copy_from_slice(&u64::MAX.to_le_bytes());
        assert!(matches!(
            next_in_chunk(&rest, rest.len() as u64, 1 << 20),
            NextRecord::TooLarge(op::MESSAGE, u64::MAX)
        ));
        // Within the chunk but past the bytes at hand (a cut file): short, not beyond.
        rest[1..9].copy_from_slice(&10u64.to_le_bytes());
        assert!(matches!(
            next_in_chunk(&rest[..12], rest.len() as u64, 1 << 20),
            NextRecord::Short
        ));
        assert!(matches!(
            next_in_chunk(&rest, rest.len() as u64, 1 << 20),
            NextRecord::Record(op::MESSAGE, 10)
        ));
    }

    #[test]
    fn a_record_longer_than_its_uncompressed_chunk_is_a_clear_error() {
        // Magic, a record inside an uncompressed chunk claiming 1000 bytes where 20 are left,
        // then bytes after the chunk that a reader going past its end would take for records.
        let mut inner = framed(op::METADATA, &[0; 20]);
        inner[1..9].copy_from_slice(&1000u64.to_le_bytes());
        let mut file = ::mcap::MAGIC.to_vec();
        file.extend(uncompressed_chunk(&inner));
        file.extend([0xff; 64]);
        let e = read_from(
            &file[..],
            Path::new("hand.mcap"),
            &ReadOptions::default(),
            Some(file.len() as u64),
        )
        .unwrap_err();
        let text = e.to_string();
        assert!(text.contains("hand.mcap"), "{text}");
        assert!(
            text.contains("after 0 record(s), 66 byte(s)")
                && text.contains("record 1 (in the chunk at byte 8): length 1000 bytes, beyond the 20 byte(s) left in the chunk"),
            "{text}"
        );
    }
}
