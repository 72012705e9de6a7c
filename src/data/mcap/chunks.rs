//! The chunk pipeline: each chunk is checked, decompressed, CRC-checked and its canonical
//! JSON frames parsed ahead on the thread pool ([`prepare_chunk`]) while the reader reads on,
//! then its records are walked in file order ([`Reading::chunk`], [`Reading::flush`]).

use super::decode::PreParsed;
use super::records::plain;
use super::{Reading, Step};
use crate::data::{DataError, Resource};
use ::mcap::records::op;
use ::mcap::McapError;
use std::io::Read;

/// The bytes of a chunk record before its records field: start and end time, uncompressed
/// size, CRC and compression length (8 + 8 + 8 + 4 + 4), the compression string, then the
/// compressed size (8).
const CHUNK_FIXED: usize = 32;

/// Buffers reused across chunks, so a file of many chunks allocates a few times only.
#[derive(Default)]
pub(super) struct ChunkBuffers {
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

impl Reading<'_> {
    /// Take a chunk record's `body` (everything after its opcode and length `len`; fewer bytes
    /// than `len` when the file ends inside it; `start` is its offset in the file, `bytes` the
    /// bytes read so far). It is prepared ([`prepare_chunk`]: header, decompression, CRC,
    /// canonical frames) on the thread pool while the reader reads on, and read in order once
    /// [`CHUNKS_AHEAD`] chunks are taken after it, or by [`Reading::flush`]. Returns what
    /// reading the chunk that came due came to: the step, and the file offset the damage is
    /// reported at.
    pub(super) fn chunk(
        &mut self,
        body: &[u8],
        len: u64,
        start: u64,
        bytes: u64,
    ) -> Result<(Step, Option<u64>), DataError> {
        // The budget left before the chunks ahead are read: looser than when this chunk is
        // read (checked again then), so at most CHUNKS_AHEAD + 1 budgets are held at once.
        let room = self.acc.budget.remaining(Resource::DecodedBytes);
        let limit = self.limit;
        let out = self.bufs.spare.pop().unwrap_or_default();
        // The reader's buffer moves on: the chunk is copied for the pool.
        let body = body.to_vec();
        let (tx, ready) = std::sync::mpsc::sync_channel(1);
        let prepare = move || {
            let prepared = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                let mut zstd = ZSTD.take();
                let prepared = prepare_chunk(&body, len, start, (room, limit), &mut zstd, out);
                ZSTD.set(zstd);
                prepared
            }))
            .unwrap_or_else(|_| Prepared::Damage(format!("chunk at byte {start}: unreadable")));
            // The receiver is gone only when reading stopped before this chunk.
            let _ = tx.send(prepared);
        };
        // On a pool thread too (the command line's main thread is one; a directory's
        // recordings are read in parallel): the wait for it runs the pool's pending jobs.
        rayon::spawn(prepare);
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
    pub(super) fn flush(&mut self) -> Result<(Step, Option<u64>), DataError> {
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
        let prepared = wait_for(&d.ready)
            .unwrap_or_else(|| Prepared::Damage(format!("chunk at byte {}: unreadable", d.start)));
        let (step, at) = match prepared {
            Prepared::Damage(why) => (Step::Damage(why), None),
            Prepared::Unsupported(c) => {
                let why = plain(&McapError::UnsupportedCompression(c.clone()));
                self.unsupported_compression = Some(c);
                (Step::Damage(why), None)
            }
            // What the chunk declares is refused before its records are read.
            Prepared::OverBudget(size) => {
                // The budget only shrinks: what did not fit then does not fit now.
                self.acc.afford(Resource::DecodedBytes, size)?;
                let why = format!("chunk at byte {}: {size} bytes declared", d.start);
                (Step::Damage(why), None)
            }
            Prepared::Records(r) => {
                let result = match r.uncompressed {
                    Some(size) => self
                        .acc
                        .afford(Resource::DecodedBytes, size)
                        .and_then(|()| self.chunk_records(&r, d.start)),
                    None => self.chunk_records(&r, d.start),
                };
                self.bufs.spare.push(r.out);
                result?
            }
        };
        if let Step::Damage(_) = step {
            return Ok((step, at.or(Some(d.bytes))));
        }
        if let Step::Next = step {
            for (len, _) in d.counted {
                self.tally(len)?;
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

/// A chunk taken by [`Reading::chunk`], waiting to be read in order.
pub(super) struct Deferred {
    /// Where the pool sends the chunk prepared.
    ready: std::sync::mpsc::Receiver<Prepared>,
    /// The chunk's offset in the file.
    start: u64,
    /// The bytes read when the chunk was taken.
    bytes: u64,
    /// Records after it that are only counted (message indexes follow every chunk): their
    /// lengths and the bytes read when each was, counted once the chunk is read, so the
    /// chunk is read beside the next one.
    pub(super) counted: Vec<(usize, u64)>,
}

/// A chunk made ready to read by [`prepare_chunk`].
enum Prepared {
    /// Damaged before its records (why).
    Damage(String),
    /// Its compression is not supported (the name).
    Unsupported(String),
    /// It declares more decompressed bytes (this many) than the budget had left when it was
    /// taken.
    OverBudget(u64),
    /// Its records.
    Records(ChunkRecords),
}

/// What `ready` brings (None when its sender is gone). A pool thread runs the pool's pending
/// jobs while it waits, since the chunk may be one of them (in a pool of one thread it always
/// is); once the pool has none left, the chunk is being prepared on another thread and the
/// wait blocks.
fn wait_for(ready: &std::sync::mpsc::Receiver<Prepared>) -> Option<Prepared> {
    use std::sync::mpsc::TryRecvError;
    loop {
        match ready.try_recv() {
            Ok(prepared) => return Some(prepared),
            Err(TryRecvError::Disconnected) => return None,
            Err(TryRecvError::Empty) => {
                if rayon::yield_now() != Some(rayon::Yield::Executed) {
                    return ready.recv().ok();
                }
            }
        }
    }
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
/// records in one go into `out` (at most `room` bytes, what the budget has left), compute their CRC and
/// parse the canonical JSON frames of its messages (records longer than `limit` are left to
/// the ordered read, which reports them). Touches no reading state, so it runs beside the
/// ordered read of the chunk before.
fn prepare_chunk(
    body: &[u8],
    len: u64,
    start: u64,
    (room, limit): (u64, usize),
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
                _ => return Prepared::OverBudget(uncompressed_size),
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

#[cfg(test)]
mod tests {
    use super::super::{read_from, write_json};
    use super::*;
    use crate::data::{ReadOptions, Recording};
    use std::collections::BTreeMap;
    use std::path::Path;

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
        // `f` on a thread of its own: a deadlock fails the test instead of hanging it.
        fn finishes<R: Send + 'static>(what: &str, f: impl FnOnce() -> R + Send + 'static) -> R {
            let (tx, rx) = std::sync::mpsc::channel();
            std::thread::spawn(move || tx.send(f()));
            rx.recv_timeout(std::time::Duration::from_secs(120))
                .unwrap_or_else(|_| panic!("{what} does not finish"))
        }
        let pool = |n: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .unwrap()
        };
        // A pool of one thread, busy reading: its chunks cannot be handed to another.
        let own = bytes.clone();
        let inside = finishes("a pool of one", move || pool(1).install(|| read(&own)));
        // Each of a pool's two threads reading a recording of its own (a directory): each
        // waits for chunks that only the two of them can prepare.
        let own = bytes.clone();
        let (first, second) = finishes("two pool threads reading side by side", move || {
            pool(2).install(|| rayon::join(|| read(&own), || read(&own)))
        });
        // The command line's pool: the calling thread is its thread 0 and reads outside any
        // parallel step; the other thread prepares the chunks it hands out.
        let own = bytes.clone();
        let main = finishes("the pool's own thread 0", move || {
            let _pool = rayon::ThreadPoolBuilder::new()
                .num_threads(2)
                .use_current_thread()
                .build()
                .unwrap();
            read(&own)
        });
        for parsed in [&outside, &inside, &first, &second, &main] {
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
