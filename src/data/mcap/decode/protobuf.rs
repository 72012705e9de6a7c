//! Protobuf (Foxglove) messages: fields read from a message decoded against the schema's
//! own descriptor.

use super::json::JStamp;
use prost_reflect::{DynamicMessage, MessageDescriptor, ReflectMessage, Value};

/// Field `name` of a protobuf message, or what was expected.
pub(super) fn pb_field<'a>(
    m: &'a DynamicMessage,
    name: &str,
) -> Result<std::borrow::Cow<'a, Value>, String> {
    m.get_field_by_name(name).ok_or_else(|| {
        format!(
            "a field {name:?} in {} (the schema lacks it)",
            m.descriptor().full_name()
        )
    })
}

/// Field `name` as f64 (foxglove vectors and points are doubles).
pub(super) fn pb_f64(m: &DynamicMessage, name: &str) -> Result<f64, String> {
    let v = pb_field(m, name)?;
    match *v {
        Value::F64(x) => Ok(x),
        Value::F32(x) => Ok(x as f64),
        ref other => Err(format!(
            "a number in {}.{name}, found {other:?}",
            m.descriptor().full_name()
        )),
    }
}

/// Field `name` as an integer of any protobuf width.
fn pb_int(m: &DynamicMessage, name: &str) -> Result<i64, String> {
    let v = pb_field(m, name)?;
    match *v {
        Value::I64(x) => Ok(x),
        Value::I32(x) => Ok(x as i64),
        Value::U32(x) => Ok(x as i64),
        Value::U64(x) => i64::try_from(x).map_err(|_| format!("{name} {x} out of range")),
        ref other => Err(format!(
            "an integer in {}.{name}, found {other:?}",
            m.descriptor().full_name()
        )),
    }
}

/// The message's `timestamp` (google.protobuf.Timestamp) in ns, `None` when it is not set.
pub(super) fn pb_stamp(m: &DynamicMessage) -> Result<Option<i64>, String> {
    if !m.has_field_by_name("timestamp") {
        return Ok(None);
    }
    let v = pb_field(m, "timestamp")?;
    let ts = v
        .as_message()
        .ok_or("a google.protobuf.Timestamp message in timestamp")?;
    let (sec, nanos) = (pb_int(ts, "seconds")?, pb_int(ts, "nanos")?);
    JStamp::Parts { sec, nsec: nanos }.ns().map(Some)
}

/// Decode a protobuf message against its descriptor.
pub(super) fn pb_decode(desc: &MessageDescriptor, data: &[u8]) -> Result<DynamicMessage, String> {
    DynamicMessage::decode(desc.clone(), data)
        .map_err(|e| format!("protobuf {}: {e}", desc.full_name()))
}

/// How many times the top-level field `name` of `desc` occurs in the encoded message `data`
/// (the entries of a repeated message field), counted on the wire without decoding: what
/// decoding would allocate for is known, and charged, first. Stops at bytes that are not
/// protobuf (decoding then says what is wrong).
pub(super) fn pb_count(desc: &MessageDescriptor, name: &str, data: &[u8]) -> usize {
    let Some(number) = desc.get_field_by_name(name).map(|f| f.number()) else {
        return 0;
    };
    let mut at = 0usize;
    let varint = |at: &mut usize| -> Option<u64> {
        let mut v = 0u64;
        for shift in (0..64).step_by(7) {
            let b = *data.get(*at)?;
            *at += 1;
            v |= u64::from(b & 0x7f) << shift;
            if b < 0x80 {
                return Some(v);
            }
        }
        None
    };
    let mut n = 0;
    while at < data.len() {
        let Some(key) = varint(&mut at) else {
            break;
        };
        let skip = match key & 7 {
            0 => varint(&mut at).map(|_| 0),
            1 => Some(8),
            2 => varint(&mut at),
            5 => Some(4),
            // Groups (long deprecated) and invalid wire types: decoding reports them.
            _ => None,
        };
        let Some(end) = skip
            .and_then(|s| usize::try_from(s).ok())
            .and_then(|s| at.checked_add(s))
            .filter(|&e| e <= data.len())
        else {
            break;
        };
        if key >> 3 == u64::from(number) && key & 7 == 2 {
            n += 1;
        }
        at = end;
    }
    n
}
