//! Records: the limits on their lengths, the checks before parsing, and reading one record
//! (schema, channel, message, metadata) into the reading state.

use super::decode::{decode, decoder_for, Failed, PreFrame, Reject};
use super::{Channel, ChannelState, Reading, Step};
use crate::data::{DataError, Resource};
use ::mcap::records::{op, MessageHeader, Metadata, Record};
use ::mcap::McapError;

/// The largest record (or decompressed chunk record) read from a file of `size` bytes: 256
/// times the file (compressed chunks may hold records larger than the file), at least 1 MiB,
/// at most 256 MiB; 256 MiB when the size is unknown.
pub fn record_limit(size: Option<u64>) -> usize {
    const MIB: u64 = 1 << 20;
    let limit = size.map_or(256 * MIB, |s| s.saturating_mul(256).clamp(MIB, 256 * MIB));
    limit as usize
}

/// Check that every length field of a Schema, Channel, Message or Metadata record fits in
/// the record, so parsing it allocates no more than the record holds; returns the entries of
/// its map (channel or metadata), which parsing allocates for one by one.
fn check_lengths(opcode: u8, data: &[u8]) -> Result<u64, String> {
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
        fn map(&mut self, what: &str) -> Result<u64, String> {
            let n = self.len(what)?;
            let end = self.at;
            self.skip(n, what)?;
            let mut inner = Cur {
                d: &self.d[end..end + n],
                at: 0,
            };
            let mut entries = 0;
            while inner.at < n {
                inner.string(what)?;
                inner.string(what)?;
                entries += 1;
            }
            Ok(entries)
        }
    }
    let mut c = Cur { d: data, at: 0 };
    match opcode {
        op::SCHEMA => {
            c.skip(2, "schema id")?;
            c.string("schema name")?;
            c.string("schema encoding")?;
            c.string("schema data").map(|_| 0)
        }
        op::CHANNEL => {
            c.skip(4, "channel ids")?;
            c.string("topic")?;
            c.string("message encoding")?;
            c.map("channel metadata")
        }
        op::MESSAGE => c.skip(22, "message header").map(|_| 0),
        op::METADATA => {
            c.string("metadata name")?;
            c.map("metadata")
        }
        _ => Ok(0),
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
pub(super) fn plain(err: &McapError) -> String {
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

/// The records read; the others are only counted.
pub(super) const USED_RECORDS: [u8; 4] = [op::SCHEMA, op::CHANNEL, op::MESSAGE, op::METADATA];

impl Reading<'_> {
    /// The damage text of a record longer than the limit.
    pub(super) fn too_large(&self, opcode: u8, len: u64) -> String {
        format!(
            "record (opcode {opcode:#04x}) of {len} bytes: more than the {}-byte limit for a file of this size",
            self.limit
        )
    }

    /// Count a record of `len` bytes, charged to the budget of decoded bytes (a bomb of
    /// zeros stops there instead of running for minutes).
    pub(super) fn tally(&mut self, len: usize) -> Result<(), DataError> {
        self.records += 1;
        self.acc.budget.charge(Resource::DecodedBytes, len as u64)
    }

    /// Read one record (outside chunks or inside one); `pre` is the message's canonical frame
    /// when it was parsed ahead.
    pub(super) fn record(
        &mut self,
        opcode: u8,
        data: &[u8],
        pre: Option<PreFrame<'_>>,
    ) -> Result<Step, DataError> {
        let (path, opts) = (self.path, self.opts);
        self.tally(data.len())?;
        let records = self.records;
        // Only these records are used; the mcap crate sizes strings from their length
        // fields before checking them, so their lengths are checked here first.
        if !USED_RECORDS.contains(&opcode) {
            return Ok(Step::Next);
        }
        match check_lengths(opcode, data) {
            // Each entry is allocated for as the record is parsed: charged first.
            Ok(entries) => self.acc.budget.charge(Resource::MetadataEntries, entries)?,
            Err(why) => {
                return Ok(Step::Damage(format!(
                    "record {records} (opcode {opcode:#04x}): {why}"
                )))
            }
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
                let schema = (header.name, header.encoding, data);
                // Writers may repeat a schema (in every chunk): the same one again is kept
                // as it is, decoded once.
                if self.schemas.get(&header.id) != Some(&schema) {
                    self.acc.budget.charge(Resource::Schemas, 1)?;
                    self.decoders.retain(|(id, _), _| *id != header.id);
                    self.schemas.insert(header.id, schema);
                }
            }
            Record::Channel(c) => {
                // The first definition of a channel holds (as before); a repeat costs nothing.
                if self.channels.contains_key(&c.id) {
                    return Ok(Step::Next);
                }
                self.acc.budget.charge(Resource::Channels, 1)?;
                let state = if !opts.topics.is_empty() && !opts.topics.contains(&c.topic) {
                    ChannelState::Ignored("not chosen by --topic".into())
                } else {
                    let schemas = &self.schemas;
                    let decoder = self
                        .decoders
                        .entry((c.schema_id, c.message_encoding))
                        .or_insert_with_key(|(id, encoding)| {
                            let (sname, senc, sdata) = schemas
                                .get(id)
                                .map(|(n, e, d)| (n.as_str(), e.as_str(), d.as_slice()))
                                .unwrap_or_default();
                            decoder_for(encoding, sname, senc, sdata)
                        });
                    match decoder.clone() {
                        Ok(d) => ChannelState::Markers(d),
                        Err(Reject::Unsupported(why)) => {
                            ChannelState::Ignored(format!("{why} is not supported"))
                        }
                        Err(Reject::Invalid(why)) => ChannelState::Ignored(why),
                    }
                };
                self.channels.insert(
                    c.id,
                    Channel {
                        topic: c.topic,
                        state,
                        decoded: 0,
                    },
                );
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
                    Err(_) => Err(Failed::Message(format!(
                        "a log_time below 2^63 ns (year 2262), found {}",
                        header.log_time
                    ))),
                };
                match result {
                    Ok(_) => ch.decoded += 1,
                    Err(Failed::Budget(e)) => return Err(e),
                    Err(Failed::Message(why)) if ch.decoded == 0 => {
                        ch.state = ChannelState::Ignored(format!(
                            "its first message is not marker data: {why}"
                        ));
                    }
                    Err(Failed::Message(why)) => {
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
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

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
}
