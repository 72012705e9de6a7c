//! The column labels of a pandas table that PyTables stores as a protocol-0 pickle (DeepLabCut's
//! HDF5 output, `values_block_0_kind`): the pickle is checked to be a list of label tuples and
//! nothing else, so that no attribute expands without bound, then decoded by `serde-pickle`.

use crate::data::DataError;
use std::collections::HashMap;

/// What one decoded string costs besides its text: the decoder's value and the label's
/// `String`, so that many empty strings count too.
const STRING_COST: u64 = 64;

/// The most column-label strings a pickled label list may expand to (a 20-animal, 50-part
/// DeepLabCut table has 3,000 columns of 4 labels).
const MAX_LABEL_STRINGS: usize = 1 << 20;

/// Column labels from the protocol-0 pickle PyTables stores: a list of tuples of strings (or of
/// strings, for one level). Only that shape is accepted (see [`check_label_pickle`]); the bytes
/// it would decode to (memo references copied) are passed to `charge`, which may refuse the
/// file (the outer `Err`), before `serde-pickle` decodes it; the inner `Err` says what was
/// found.
pub(super) fn unpickle_labels(
    raw: &[u8],
    charge: impl FnOnce(u64) -> Result<(), DataError>,
) -> Result<Result<Vec<Vec<String>>, String>, DataError> {
    // A fixed-length HDF5 string: NUL padded.
    let end = raw.iter().rposition(|&b| b != 0).map_or(0, |i| i + 1);
    let raw = &raw[..end];
    match check_label_pickle(raw) {
        Ok(bytes) => charge(bytes)?,
        Err(found) => return Ok(Err(found)),
    }
    Ok(decode_labels(raw))
}

/// Decode a label pickle that [`check_label_pickle`] accepted.
fn decode_labels(raw: &[u8]) -> Result<Vec<Vec<String>>, String> {
    let value =
        serde_pickle::value_from_slice(raw, serde_pickle::DeOptions::new().decode_strings())
            .map_err(|e| e.to_string())?;
    let text = |v: &serde_pickle::Value| match v {
        serde_pickle::Value::String(s) => Ok(s.clone()),
        serde_pickle::Value::Bytes(b) => Ok(String::from_utf8_lossy(b).into_owned()),
        other => Err(format!("the label {other:?}")),
    };
    let serde_pickle::Value::List(items) = value else {
        return Err("not a list".into());
    };
    items
        .iter()
        .map(|item| match item {
            serde_pickle::Value::Tuple(parts) => parts.iter().map(text).collect(),
            other => Ok(vec![text(other)?]),
        })
        .collect()
}

/// Check that `raw` is exactly what `pickle.dumps(labels, 0)` writes for a list of tuples of
/// strings: `(l` then, per label, a string or a tuple `(` ... `t` (each part a string, number or
/// memo reference, new objects optionally memoized with `p`) or a memo reference `g`, followed by
/// `a`; then `.`. This keeps the nesting at two and memo entries from being copied, and counts
/// the strings the list expands to (references included), refusing more than
/// [`MAX_LABEL_STRINGS`]; `Ok` is the bytes they decode to (each reference copies its
/// entry's), for the caller to charge: no pickle can then make the decoder allocate without
/// bound.
fn check_label_pickle<'a>(raw: &'a [u8]) -> Result<u64, String> {
    let mut ops = Ops { raw, at: 0 };
    // Each memo entry's size: strings (1 for a scalar, its length for a tuple) and the bytes
    // they decode to.
    type Size = (usize, u64);
    let mut memo: HashMap<&'a [u8], Size> = HashMap::new();
    let put = |ops: &mut Ops<'a>, n: Size, memo: &mut HashMap<&'a [u8], Size>| {
        if ops.peek() == Some(b'p') {
            let (_, id) = ops.next()?;
            memo.insert(id, n);
        }
        Ok::<(), String>(())
    };
    ops.expect(b'(')?;
    ops.expect(b'l')?;
    // The list itself is put in the memo too, but nothing may refer to it.
    if ops.peek() == Some(b'p') {
        ops.next()?;
    }
    let (mut total, mut bytes) = (0usize, 0u64);
    // A scalar's size: one string of its argument's length.
    let scalar = |arg: &[u8]| (1, arg.len() as u64 + STRING_COST);
    loop {
        let n = match ops.next()? {
            (b'.', _) if ops.at == raw.len() => return Ok(bytes),
            (b'(', _) => {
                let mut n: Size = (0, STRING_COST);
                loop {
                    let part = match ops.next()? {
                        (b't', _) => break,
                        (b'g', id) => match memo.get(id) {
                            Some(&(1, b)) => (1, b),
                            _ => return Err(ops.unexpected(b'g', "a label part")),
                        },
                        (op, arg) if SCALARS.contains(&op) => {
                            let part = scalar(arg);
                            put(&mut ops, part, &mut memo)?;
                            part
                        }
                        (op, _) => return Err(ops.unexpected(op, "a label part")),
                    };
                    n = (n.0 + 1, n.1.saturating_add(part.1));
                }
                put(&mut ops, n, &mut memo)?;
                n
            }
            (b'g', id) => *memo
                .get(id)
                .ok_or_else(|| format!("a reference to memo {:?} never put", ascii(id)))?,
            (op, arg) if SCALARS.contains(&op) => {
                let n = scalar(arg);
                put(&mut ops, n, &mut memo)?;
                n
            }
            (op, _) => return Err(ops.unexpected(op, "a label")),
        };
        ops.expect(b'a')?;
        total += n.0;
        bytes = bytes.saturating_add(n.1);
        if total > MAX_LABEL_STRINGS {
            return Err(format!("more than {MAX_LABEL_STRINGS} label strings"));
        }
    }
}

/// Protocol-0 opcodes of one scalar, each with a line argument: unicode, byte string, int,
/// long, float; and None.
const SCALARS: [u8; 6] = [b'V', b'S', b'I', b'L', b'F', b'N'];

/// Protocol-0 opcodes, each with its line argument (empty for one-byte opcodes).
struct Ops<'a> {
    raw: &'a [u8],
    at: usize,
}

impl<'a> Ops<'a> {
    fn peek(&self) -> Option<u8> {
        self.raw.get(self.at).copied()
    }

    fn next(&mut self) -> Result<(u8, &'a [u8]), String> {
        let op = self.peek().ok_or("a pickle that ends before its stop")?;
        self.at += 1;
        if !b"VSILFpg".contains(&op) {
            return Ok((op, &[]));
        }
        let rest = &self.raw[self.at..];
        let n = rest
            .iter()
            .position(|&b| b == b'\n')
            .ok_or("an opcode argument without its newline")?;
        self.at += n + 1;
        Ok((op, &rest[..n]))
    }

    fn expect(&mut self, want: u8) -> Result<(), String> {
        match self.next()? {
            (op, _) if op == want => Ok(()),
            (op, _) => Err(self.unexpected(op, &format!("{:?}", want as char))),
        }
    }

    fn unexpected(&self, op: u8, wanted: &str) -> String {
        format!(
            "opcode {:?} at byte {} where {wanted} belongs",
            op as char,
            self.at.saturating_sub(1)
        )
    }
}

fn ascii(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pytables_label_pickles_decode_and_others_are_refused() {
        // As PyTables writes `[("s", "a", "x"), ("s", "a", "y")]` (pickle.dumps(v, 0)).
        let ok = b"(lp0\n(Vs\np1\nVa\np2\nVx\np3\ntp4\na(g1\ng2\nVy\np5\ntp6\na.";
        assert_eq!(
            unpickle_labels(ok, |_| Ok(())).unwrap().unwrap(),
            vec![vec!["s", "a", "x"], vec!["s", "a", "y"]]
        );
        // Python 2's byte strings, NUL padding, one level.
        assert_eq!(
            unpickle_labels(b"(lp0\nS'a b'\np1\naS'c'\np2\na.\0\0", |_| Ok(()))
                .unwrap()
                .unwrap(),
            vec![vec!["a b"], vec!["c"]]
        );
        // Strings referenced again, as pickle writes a repeated scorer or bodypart.
        let refs = b"(lp0\n(Vx\np1\ng1\ng1\ntp2\na(g1\nVy\np3\ntp4\na.";
        assert_eq!(
            unpickle_labels(refs, |_| Ok(())).unwrap().unwrap(),
            vec![vec!["x", "x", "x"], vec!["x", "y"]]
        );
        for bad in [
            &b"\x80\x02]q\x00."[..],            // protocol 2
            b"(lp0\nVx\np1\np2\na.",            // a memo entry put twice
            b"(lp0\ng0\na.",                    // the list inside itself
            b"(lp0\n(lp1\na.",                  // a list in the list
            b"(lp0\nc__builtin__\nlist\n(tRa.", // a global call
            b"(lp0\nVx\na",                     // no stop
            b"(lp0\nVx\na.V",                   // past the stop
            b"(lp0\nI1\na.",                    // a number for a label
        ] {
            assert!(
                unpickle_labels(bad, |_| Ok(())).unwrap().is_err(),
                "{:?}",
                ascii(bad)
            );
        }
        // A tuple of 1,000 strings referenced 2,000 times: 2 million strings, refused.
        let mut big = b"(lp0\n(".to_vec();
        for i in 0..1000 {
            big.extend(format!("Vp{i}\n").bytes());
        }
        big.extend(b"tp1\na");
        for _ in 0..2000 {
            big.extend(b"g1\na");
        }
        big.push(b'.');
        assert!(unpickle_labels(&big, |_| Ok(()))
            .unwrap()
            .unwrap_err()
            .contains("more than"));
        // One long string referenced many times: few strings, many bytes, all counted.
        let mut wide = b"(lp0\nV".to_vec();
        wide.extend([b'a'; 1000]);
        wide.extend(b"\np1\na");
        for _ in 0..99 {
            wide.extend(b"g1\na");
        }
        wide.push(b'.');
        let mut charged = 0;
        unpickle_labels(&wide, |n| {
            charged = n;
            Ok(())
        })
        .unwrap()
        .unwrap();
        assert_eq!(charged, 100 * (1000 + STRING_COST));
    }
}
