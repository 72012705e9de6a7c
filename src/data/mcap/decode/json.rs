//! JSON marker messages: the serde types, and the canonical frame layout read byte by byte
//! (also parsed ahead, per chunk, on the thread pool).

use serde::Deserialize;

/// A JSON time stamp: `{"sec", "nsec"}` (also `nanosec`, `nanos`) or, as Foxglove tools
/// write it, a float of seconds.
#[derive(Deserialize)]
#[serde(untagged)]
pub(super) enum JStamp {
    Parts {
        sec: i64,
        #[serde(default, alias = "nanosec", alias = "nanos")]
        nsec: i64,
    },
    Seconds(f64),
}

impl JStamp {
    /// Nanoseconds, or what was expected when the stamp does not fit in i64 nanoseconds.
    pub(super) fn ns(&self) -> Result<i64, String> {
        match *self {
            JStamp::Parts { sec, nsec } => sec
                .checked_mul(1_000_000_000)
                .and_then(|s| s.checked_add(nsec))
                .ok_or_else(|| {
                    format!("a timestamp within +-292 years of 1970, found sec {sec}, nsec {nsec}")
                }),
            JStamp::Seconds(s) => seconds_to_ns(s),
        }
    }
}

/// Float seconds as nanoseconds, when they fit.
fn seconds_to_ns(s: f64) -> Result<i64, String> {
    if s.is_finite() && s.abs() < 9.2e9 {
        // Whole seconds and the fraction apart: 1.7e9 s times 1e9 would round to 256 ns.
        let whole = s.floor();
        Ok(whole as i64 * 1_000_000_000 + ((s - whole) * 1e9).round() as i64)
    } else {
        Err(format!(
            "a timestamp in seconds within +-9.2e9 (292 years), found {s}"
        ))
    }
}

#[derive(Deserialize)]
pub(super) struct JHeader {
    pub(super) stamp: Option<JStamp>,
}

#[derive(Deserialize)]
pub(super) struct JPoint {
    pub(super) x: Option<f64>,
    pub(super) y: Option<f64>,
    pub(super) z: Option<f64>,
}

#[derive(Deserialize)]
pub(super) struct JMarker {
    #[serde(alias = "name", alias = "label")]
    pub(super) id: String,
    pub(super) x: Option<f64>,
    pub(super) y: Option<f64>,
    pub(super) z: Option<f64>,
}

#[derive(Deserialize)]
pub(super) struct JMsg {
    pub(super) timestamp: Option<JStamp>,
    pub(super) header: Option<JHeader>,
    pub(super) markers: Option<Vec<JMarker>>,
    pub(super) x: Option<f64>,
    pub(super) y: Option<f64>,
    pub(super) z: Option<f64>,
    pub(super) point: Option<JPoint>,
    pub(super) position: Option<JPoint>,
}

/// The common JSON frame (a `markers` array, `{"sec", "nsec"}` stamps), read without copying
/// marker names: a message this reads, [`JMsg`] reads to the same values; any other message
/// (a stamp in float seconds, a malformed one) goes to [`JMsg`], which words the errors.
#[derive(Deserialize)]
pub(super) struct FastMsg<'a> {
    pub(super) timestamp: Option<FastStamp>,
    pub(super) header: Option<FastHeader>,
    #[serde(borrow)]
    pub(super) markers: Option<Vec<FastMarker<'a>>>,
    pub(super) x: Option<f64>,
    pub(super) y: Option<f64>,
    pub(super) z: Option<f64>,
    pub(super) point: Option<JPoint>,
    pub(super) position: Option<JPoint>,
}

/// [`JStamp::Parts`] alone.
#[derive(Deserialize)]
pub(super) struct FastStamp {
    pub(super) sec: i64,
    #[serde(default, alias = "nanosec", alias = "nanos")]
    pub(super) nsec: i64,
}

#[derive(Deserialize)]
pub(super) struct FastHeader {
    pub(super) stamp: Option<FastStamp>,
}

/// [`JMarker`] with its name borrowed from the message when it holds no escapes.
#[derive(Deserialize)]
pub(super) struct FastMarker<'a> {
    #[serde(borrow, alias = "name", alias = "label")]
    pub(super) id: std::borrow::Cow<'a, str>,
    pub(super) x: Option<f64>,
    pub(super) y: Option<f64>,
    pub(super) z: Option<f64>,
}

/// The most markers a frame read by [`canonical_frame`] holds (more go to serde).
const CANONICAL_MARKERS: usize = 8;

/// One frame in the exact layout [`write_json`] (and the Python example files) write:
/// `{"timestamp":{"sec":S,"nsec":N},"frame_id":"..","markers":[{"id":"..","x":X,"y":Y},..]}`
/// without whitespace: the stamp's parts and up to [`CANONICAL_MARKERS`] markers (name, x, y),
/// names and the frame id without escapes.
///
/// [`write_json`]: crate::data::mcap::write_json
pub(super) struct CanonicalFrame<'a> {
    pub(super) sec: i64,
    pub(super) nsec: i64,
    pub(super) len: usize,
    pub(super) markers: [(&'a str, Option<f64>, Option<f64>); CANONICAL_MARKERS],
}

/// A byte cursor over one message for [`canonical_frame`]; every method returns `None` (the
/// message then goes to serde) at anything outside the narrow layout it accepts.
struct Bytes<'a> {
    d: &'a [u8],
    at: usize,
}

impl<'a> Bytes<'a> {
    /// The literal `s` (a fixed-size array, compared without a library call).
    fn lit<const N: usize>(&mut self, s: &[u8; N]) -> Option<()> {
        let w: &[u8; N] = self.d.get(self.at..self.at + N)?.try_into().ok()?;
        (w == s).then(|| self.at += N)
    }

    fn digits(&self, from: usize) -> usize {
        self.d[from..]
            .iter()
            .take_while(|b| b.is_ascii_digit())
            .count()
    }

    /// A string without escapes or control characters: its bytes are its text.
    fn string(&mut self) -> Option<&'a str> {
        self.lit(b"\"")?;
        let start = self.at;
        let len = self.d[start..].iter().position(|&b| b == b'"')?;
        if self.d[start..start + len]
            .iter()
            .any(|&b| b == b'\\' || b < 0x20)
        {
            return None;
        }
        self.at = start + len + 1;
        // Only strings may hold other than ASCII: each is checked for UTF-8 here.
        std::str::from_utf8(&self.d[start..start + len]).ok()
    }

    /// A JSON integer of at most 18 digits (no `-0`, which serde reads as a float).
    fn int(&mut self) -> Option<i64> {
        let neg = self.lit(b"-").is_some();
        let n = self.digits(self.at);
        let digits = &self.d[self.at..self.at + n];
        if n == 0 || n > 18 || (n > 1 && digits[0] == b'0') {
            return None;
        }
        let v = digits
            .iter()
            .fold(0i64, |v, &b| v * 10 + i64::from(b - b'0'));
        if neg && v == 0 {
            return None;
        }
        self.at += n;
        Some(if neg { -v } else { v })
    }

    /// Digits from `i`: where they end and how many are significant (from the first nonzero
    /// one on, counting those already seen, `significant`), with the mantissa `m` they extend
    /// (its first 19 significant digits, wrapping beyond: a number with more is not taken
    /// here).
    fn count_digits(
        &self,
        mut i: usize,
        mut significant: usize,
        mut m: u64,
    ) -> (usize, usize, u64) {
        while let Some(&c) = self.d.get(i) {
            if !c.is_ascii_digit() {
                break;
            }
            if significant > 0 || c != b'0' {
                significant += 1;
            }
            m = m.wrapping_mul(10).wrapping_add(u64::from(c - b'0'));
            i += 1;
        }
        (i, significant, m)
    }

    /// `null`, or a JSON number with a fraction or an exponent (how serde_json writes every
    /// f64) of at most 19 significant digits and a finite value: exact input to both std's and
    /// serde_json's correctly rounded parsers, so the same f64. Most marker positions have few
    /// digits and are computed here in one rounding ([`exact_decimal`]); the rest go to std.
    fn float(&mut self) -> Option<Option<f64>> {
        if self.lit(b"null").is_some() {
            return Some(None);
        }
        let start = self.at;
        let negative = self.d.get(start) == Some(&b'-');
        let int_start = start + usize::from(negative);
        let (mut i, mut significant, mut m) = self.count_digits(int_start, 0, 0);
        if i == int_start || (i - int_start > 1 && self.d[int_start] == b'0') {
            return None;
        }
        let mut fraction = 0;
        if self.d.get(i) == Some(&b'.') {
            let (end, sig, mantissa) = self.count_digits(i + 1, significant, m);
            if end == i + 1 {
                return None;
            }
            fraction = end - i - 1;
            (i, significant, m) = (end, sig, mantissa);
        }
        let mut exponent = None;
        if matches!(self.d.get(i), Some(b'e' | b'E')) {
            i += 1;
            let minus = self.d.get(i) == Some(&b'-');
            if matches!(self.d.get(i), Some(b'+' | b'-')) {
                i += 1;
            }
            let n = self.digits(i);
            if n == 0 || n > 4 {
                return None;
            }
            let e = self.d[i..i + n]
                .iter()
                .fold(0i64, |e, &c| e * 10 + i64::from(c - b'0'));
            i += n;
            exponent = Some(if minus { -e } else { e });
        }
        if (fraction == 0 && exponent.is_none()) || significant > 19 {
            return None;
        }
        // At most 19 significant digits (m fits in u64) and 4 of exponent; the fraction's
        // digits are bounded by the message's length.
        let exp10 = exponent.unwrap_or(0) - fraction as i64;
        let v = match exact_decimal(m, exp10) {
            Some(v) if negative => -v,
            Some(v) => v,
            None => std::str::from_utf8(&self.d[start..i]).ok()?.parse().ok()?,
        };
        if !v.is_finite() {
            return None;
        }
        self.at = i;
        Some(Some(v))
    }
}

/// `m` times 10^`exp10` when one IEEE operation gives it correctly rounded (Clinger's fast
/// path): `m` at most 2^53 and 10^|exp10| at most 10^22 are both exact doubles, so their
/// product or quotient is rounded once, which is the correctly rounded value std's and
/// serde_json's parsers return too. `None` outside that range.
fn exact_decimal(m: u64, exp10: i64) -> Option<f64> {
    /// 10^0 to 10^22, each exact in f64.
    const POW10: [f64; 23] = [
        1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
        1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
    ];
    if m > 1 << 53 {
        return None;
    }
    let p = *POW10.get(usize::try_from(exp10.unsigned_abs()).ok()?)?;
    let m = m as f64;
    Some(if exp10 < 0 { m / p } else { m * p })
}

/// Read a frame in the exact layout of [`CanonicalFrame`], or `None` for any other message
/// (spaces, other keys or key order, escapes, integers where floats are written, more
/// markers), which serde then reads. What this accepts, serde reads to the same values.
pub(super) fn canonical_frame(data: &[u8]) -> Option<CanonicalFrame<'_>> {
    // Outside its strings a frame is ASCII literals and digits, matched byte by byte; the
    // strings are checked for UTF-8 as they are read.
    let mut b = Bytes { d: data, at: 0 };
    b.lit(b"{\"timestamp\":{\"sec\":")?;
    let sec = b.int()?;
    b.lit(b",\"nsec\":")?;
    let nsec = b.int()?;
    b.lit(b"},\"frame_id\":")?;
    b.string()?;
    b.lit(b",\"markers\":[")?;
    let mut frame = CanonicalFrame {
        sec,
        nsec,
        len: 0,
        markers: [("", None, None); CANONICAL_MARKERS],
    };
    loop {
        if frame.len == CANONICAL_MARKERS {
            return None;
        }
        b.lit(b"{\"id\":")?;
        let id = b.string()?;
        b.lit(b",\"x\":")?;
        let x = b.float()?;
        b.lit(b",\"y\":")?;
        let y = b.float()?;
        b.lit(b"}")?;
        frame.markers[frame.len] = (id, x, y);
        frame.len += 1;
        if b.lit(b",").is_none() {
            break;
        }
    }
    b.lit(b"]}")?;
    (b.at == data.len()).then_some(frame)
}

/// One marker of a frame parsed ahead: where its name lies in the message, and x, y.
pub(crate) type PreMarker = (std::ops::Range<usize>, Option<f64>, Option<f64>);

/// A chunk's canonical JSON frames, parsed ahead on the thread pool while the chunks before
/// are read (see [`Reading::chunk`]): per message record in chunk order, its stamp's parts and
/// its markers' span in `markers`, or `None` when the message is not a canonical frame (it is
/// then decoded as before, in order).
///
/// [`Reading::chunk`]: crate::data::mcap::Reading::chunk
#[derive(Default)]
pub(crate) struct PreParsed {
    frames: Vec<Option<(i64, i64, std::ops::Range<usize>)>>,
    markers: Vec<PreMarker>,
}

impl PreParsed {
    /// Parse the payloads of `messages` (each a message record's body) with
    /// [`canonical_frame`].
    pub(crate) fn parse(messages: &[&[u8]]) -> PreParsed {
        let mut out = PreParsed::default();
        for body in messages {
            let frame = body.get(22..).and_then(|payload| {
                let f = canonical_frame(payload)?;
                let first = out.markers.len();
                for &(id, x, y) in &f.markers[..f.len] {
                    // The name is a slice of the payload: its offset locates it.
                    let at = id.as_ptr() as usize - payload.as_ptr() as usize;
                    out.markers.push((at..at + id.len(), x, y));
                }
                Some((f.sec, f.nsec, first..out.markers.len()))
            });
            out.frames.push(frame);
        }
        out
    }

    /// The `k`-th message's frame, when it was canonical.
    pub(crate) fn frame(&self, k: usize) -> Option<PreFrame<'_>> {
        let (sec, nsec, r) = self.frames.get(k)?.as_ref()?;
        Some(PreFrame {
            sec: *sec,
            nsec: *nsec,
            markers: &self.markers[r.clone()],
        })
    }
}

/// A message's canonical frame parsed ahead (see [`PreParsed`]).
#[derive(Clone, Copy)]
pub(crate) struct PreFrame<'a> {
    pub(super) sec: i64,
    pub(super) nsec: i64,
    pub(super) markers: &'a [PreMarker],
}

#[cfg(test)]
mod tests {
    use super::super::{decode, xy, Decoder};
    use super::*;
    use crate::data::mcap::tf::Acc;
    use crate::data::Budget;
    use rand::{Rng, SeedableRng};

    /// Samples: marker, stamp, position bits.
    type Samples = Vec<(String, i64, Option<[u64; 2]>)>;

    /// What the serde reader alone makes of a JSON message: its samples, bit for bit.
    fn by_serde(data: &[u8]) -> Result<Samples, String> {
        let m: JMsg = serde_json::from_slice(data).map_err(|e| format!("JSON: {e}"))?;
        let stamp = m.timestamp.expect("a stamp").ns()?;
        Ok(m.markers
            .expect("markers")
            .into_iter()
            .map(|mk| {
                let p = xy(mk.x, mk.y, mk.z, None);
                (mk.id, stamp, p.map(|p| p.map(f64::to_bits)))
            })
            .collect())
    }

    /// What `decode` gives (the canonical layout first, then serde); the same as when the
    /// frame is parsed ahead in a message record, as chunks are.
    fn by_decode(data: &[u8]) -> Result<Samples, String> {
        let samples = |pre: Option<PreFrame<'_>>| -> Result<Samples, String> {
            let mut acc = Acc::new(Budget::new(std::path::Path::new("t.mcap"), 1 << 20));
            decode(&Decoder::Json, "/markers", data, 0, None, &mut acc, pre).map_err(
                |e| match e {
                    super::super::Failed::Message(why) => why,
                    super::super::Failed::Budget(e) => e.to_string(),
                },
            )?;
            let mut out = Vec::new();
            for (_, name, s) in acc.series {
                for (ns, p) in s {
                    out.push((name.clone(), ns, p.map(|p| p.map(f64::to_bits))));
                }
            }
            // decode groups by marker; by_serde lists in message order: compare by name.
            out.sort_by(|a, b| a.0.cmp(&b.0));
            Ok(out)
        };
        let record = [&[0u8; 22][..], data].concat();
        let ahead = PreParsed::parse(&[&record]);
        let direct = samples(None);
        assert_eq!(samples(ahead.frame(0)), direct, "parsed ahead");
        direct
    }

    fn frame(sec: &str, nsec: &str, x: &str, y: &str) -> String {
        format!(
            r#"{{"timestamp":{{"sec":{sec},"nsec":{nsec}}},"frame_id":"rail","markers":[{{"id":"slider","x":{x},"y":{y}}},{{"id":"bob","x":0.2350487,"y":-0.186438}}]}}"#
        )
    }

    #[test]
    fn canonical_layout_reads_what_serde_reads() {
        let numbers = [
            "6.09e-05",
            "-9.04e-05",
            "-0.0",
            "0.0",
            "1e-320",
            "5e-324",
            "2.4703282292062328e-324",
            "0.30000000000000004",
            "1.7976931348623157e308",
            "2.2250738585072014e-308",
            "123456789012345678.9",
            "0.000000000000000000001234567890123456789",
            "9007199254740993.0",
            "1E5",
            "1e+05",
            "null",
        ];
        for x in numbers {
            for y in numbers {
                let m = frame("1700000000", "5", x, y);
                let fast = canonical_frame(m.as_bytes());
                assert!(fast.is_some(), "{m}");
                let mut want = by_serde(m.as_bytes()).unwrap();
                want.sort_by(|a, b| a.0.cmp(&b.0));
                assert_eq!(by_decode(m.as_bytes()).unwrap(), want, "{m}");
            }
        }
        // Not the layout: serde reads them (or words the error) as before.
        for m in [
            frame("-0", "0", "1.0", "2.0"),
            frame("1", "0", "1", "2.0"),
            frame("1", "0", "01.5", "2.0"),
            frame("1", "0", "1.", "2.0"),
            frame("1", "0", "1e400", "2.0"),
            frame("1", "0", "12345678901234567890.5", "2.0"),
            frame("1.5", "0", "1.0", "2.0"),
            frame("9223372036854775807", "0", "1.0", "2.0"),
            frame("1", "0", "1.0", "2.0").replace("slider", "sli\\u0064er"),
            frame("1", "0", "1.0", "2.0").replace(",\"y\"", ", \"y\""),
            frame("1", "0", "1.0", "2.0") + " ",
        ] {
            assert!(canonical_frame(m.as_bytes()).is_none(), "{m}");
            let want = by_serde(m.as_bytes()).map(|mut v| {
                v.sort_by(|a, b| a.0.cmp(&b.0));
                v
            });
            assert_eq!(by_decode(m.as_bytes()), want, "{m}");
        }
    }

    #[test]
    fn canonical_names_are_checked_for_utf8_as_serde_checks_them() {
        // Non-ASCII names are read by the canonical layout, as serde reads them.
        let m = frame("3", "7", "0.5", "-0.25").replace("slider", "sl\u{e9}der");
        assert!(canonical_frame(m.as_bytes()).is_some(), "{m}");
        let mut want = by_serde(m.as_bytes()).unwrap();
        want.sort_by(|a, b| a.0.cmp(&b.0));
        assert_eq!(by_decode(m.as_bytes()).unwrap(), want);
        // Bytes that are not UTF-8, in a name or elsewhere: not the layout, and serde's error.
        let good = frame("3", "7", "0.5", "-0.25").into_bytes();
        for (at, byte) in [(good.len() / 2, 0xffu8), (1, 0xc3), (good.len() - 3, 0x80)] {
            let mut bad = good.clone();
            bad[at] = byte;
            assert!(canonical_frame(&bad).is_none());
            assert!(
                by_decode(&bad).is_err(),
                "{}",
                String::from_utf8_lossy(&bad)
            );
        }
        let mut bad = good.clone();
        let name = good.windows(6).position(|w| w == b"slider").unwrap();
        bad[name + 2] = 0xff;
        assert!(canonical_frame(&bad).is_none());
        assert_eq!(by_decode(&bad), by_serde(&bad));
    }

    /// The value serde_json (`float_roundtrip`, correctly rounded) reads for `text`, and the
    /// canonical layout's, bit for bit; `None` when the layout leaves the frame to serde.
    fn both_ways(text: &str) -> Option<(u64, u64)> {
        let m = frame("1", "0", text, "0.5");
        let fast = canonical_frame(m.as_bytes())?.markers[0].1?;
        let serde: JMsg = serde_json::from_slice(m.as_bytes()).unwrap();
        Some((
            fast.to_bits(),
            serde.markers.unwrap()[0].x.unwrap().to_bits(),
        ))
    }

    #[test]
    fn short_decimals_are_exact_on_both_sides_of_the_fast_paths_edges() {
        // Clinger's fast path takes a mantissa up to 2^53 and a power of ten up to 10^22; one
        // step past either edge goes to std's parser. Both give serde's bits.
        for text in [
            "9007199254740992.0",
            "9007199254740993.0",
            "-9007199254740992e-22",
            "9007199254740992e-23",
            "9007199254740993e22",
            "1e22",
            "1e23",
            "1e-22",
            "1e-23",
            "123456789e-22",
            "4.5e-23",
            "0.0",
            "-0.0",
            "0e5",
            "-0e-5",
            "0.000",
            "0.00000000000000000000000000012345",
            "1234567890123456789e-10",
            "0.1",
            "0.30000000000000004",
            "2.2250738585072014e-308",
            "5e-324",
            "1.7976931348623157e308",
            "-6.09e-05",
            "0.2350487",
        ] {
            let (fast, serde) = both_ways(text).unwrap_or_else(|| panic!("{text}: not taken"));
            assert_eq!(fast, serde, "{text}");
        }
        // More than 19 significant digits: left to serde.
        assert!(both_ways("1.0000000000000000000").is_none());
        // Random short decimals over the whole fast path and past it.
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for _ in 0..200_000 {
            let digits = rng.random_range(1..=17u32);
            let m = rng.random_range(0..10u64.pow(digits));
            let e = rng.random_range(-26..=26i32);
            let point = rng.random_range(0..=digits as usize);
            let s = format!("{m:0width$}", width = digits as usize);
            let (int, frac) = s.split_at(s.len() - point);
            let int = if int.is_empty() {
                "0"
            } else {
                int.trim_start_matches('0')
            };
            let int = if int.is_empty() { "0" } else { int };
            let sign = if rng.random::<bool>() { "-" } else { "" };
            for text in [
                format!("{sign}{m}e{e}"),
                format!("{sign}{int}.{frac}0"),
                format!("{sign}{int}.{frac}0E{e:+}"),
            ] {
                if let Some((fast, serde)) = both_ways(&text) {
                    assert_eq!(fast, serde, "{text}");
                }
            }
        }
    }

    #[test]
    fn canonical_floats_are_serdes_bit_for_bit() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        for k in 0..200_000 {
            let v = match k % 3 {
                0 => f64::from_bits(rng.random::<u64>()),
                1 => rng.random::<f64>() * 10f64.powi(rng.random_range(-12..12)),
                _ => (rng.random::<f64>() - 0.5) * 1e-3,
            };
            if !v.is_finite() {
                continue;
            }
            for text in [
                serde_json::to_string(&v).unwrap(),
                format!("{v:e}"),
                format!("{v:.17e}"),
                format!("{v:.9}"),
            ] {
                let m = frame("1", "0", &text, "0.5");
                let Some(f) = canonical_frame(m.as_bytes()) else {
                    continue;
                };
                let serde: JMsg = serde_json::from_slice(m.as_bytes()).unwrap();
                let want = serde.markers.unwrap()[0].x.unwrap();
                assert_eq!(f.markers[0].1.unwrap().to_bits(), want.to_bits(), "{text}");
            }
        }
    }
}
