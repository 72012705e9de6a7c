//! Structure-aware fuzzing of DeepLabCut's pickled column labels: the input describes a
//! pickle (mostly the protocol-0 list of label tuples PyTables writes, with memo puts and
//! gets, repeats, quoting and escapes, and any protocol 0-2 opcode in between), which is
//! written into the `values_block_0_kind` attribute of a DeepLabCut HDF5 table
//! (`fuzz/seeds/dlc_pickle_slot.h5`: the repo's 12-column DeepLabCut table with that
//! attribute made a 60,000-byte NUL-padded string, filled with '@'). The file then goes to
//! the reader: a recording or an error, never a panic.
#![no_main]

use appell::data::{read_recording_bytes, Format, ReadOptions};
use libfuzzer_sys::arbitrary::{self, Arbitrary};
use libfuzzer_sys::fuzz_target;

const SEED: &[u8] = include_bytes!("../seeds/dlc_pickle_slot.h5");
const SLOT: usize = 60_000;

fn slot() -> usize {
    static AT: std::sync::OnceLock<usize> = std::sync::OnceLock::new();
    *AT.get_or_init(|| {
        SEED.windows(SLOT)
            .position(|w| w.iter().all(|&b| b == b'@'))
            .expect("the seed's pickle slot")
    })
}

#[derive(Arbitrary, Debug)]
enum Text {
    Scorer,
    Slider,
    Bob,
    Coord(u8),
    Individual(u8),
    Empty,
    /// A long run of one character (memo references to it copy it).
    Long(u16, u8),
    Any(String),
    /// Bytes as they are (newlines, quotes, backslashes, invalid UTF-8).
    Bytes(Vec<u8>),
}

impl Text {
    fn bytes(&self) -> Vec<u8> {
        match self {
            Text::Scorer => b"DLC_resnet50_TESTNov4shuffle1_10".to_vec(),
            Text::Slider => b"slider".to_vec(),
            Text::Bob => b"bob".to_vec(),
            Text::Coord(i) => [&b"x"[..], b"y", b"likelihood", b"z"][*i as usize % 4].to_vec(),
            Text::Individual(i) => format!("mouse{i}").into_bytes(),
            Text::Empty => Vec::new(),
            Text::Long(n, c) => vec![*c; *n as usize % 20_000],
            Text::Any(s) => s.clone().into_bytes(),
            Text::Bytes(b) => b.clone(),
        }
    }
}

#[derive(Arbitrary, Debug)]
enum Scalar {
    /// `V` raw-unicode-escape text (backslash-u escapes, arbitrary bytes).
    Unicode(Text, bool),
    /// `S` a quoted byte string (Python repr), or a broken quoting.
    Str(Text, u8),
    Int(i64),
    Long(i128),
    Float(f64),
    FloatText(String),
    None,
}

#[derive(Arbitrary, Debug)]
enum Part {
    Scalar(Scalar, Option<u16>),
    Get(u16),
}

#[derive(Arbitrary, Debug)]
enum Item {
    Scalar(Scalar, Option<u16>),
    Tuple(Vec<Part>, Option<u16>),
    Get(u16),
    /// Any opcode, to exercise the refusals.
    Op(Op),
}

/// Protocol 0-2 opcodes that a label pickle does not hold.
#[derive(Arbitrary, Debug)]
enum Op {
    Mark,
    Stop,
    Proto(u8),
    BinUnicode(u32, Vec<u8>),
    ShortBinString(u8, Vec<u8>),
    BinInt(i32),
    BinPut(u8),
    BinGet(u8),
    LongBinGet(u32),
    List,
    EmptyList,
    Append,
    Appends,
    Tuple,
    EmptyTuple,
    Dict,
    EmptyDict,
    SetItem,
    Global(String, String),
    Reduce,
    Build,
    Inst(String, String),
    Obj,
    Pop,
    Dup,
    Raw(Vec<u8>),
}

#[derive(Arbitrary, Debug)]
struct Pickle {
    /// `(lp0\n` as PyTables writes (with or without the memo put) or `]` (protocol 2).
    head: u8,
    items: Vec<(Item, bool)>,
    /// Repeat the item list this many times.
    repeat: u8,
    /// What ends it: `.`, nothing, `.` then more bytes.
    tail: u8,
    trailing: Vec<u8>,
}

fn text_quoted(t: &[u8], how: u8) -> Vec<u8> {
    let mut out = Vec::new();
    match how % 4 {
        0 => {
            out.push(b'\'');
            for &b in t {
                match b {
                    b'\'' | b'\\' => out.extend_from_slice(&[b'\\', b]),
                    b'\n' => out.extend_from_slice(b"\\n"),
                    32..=126 => out.push(b),
                    _ => out.extend_from_slice(format!("\\x{b:02x}").as_bytes()),
                }
            }
            out.push(b'\'');
        }
        1 => {
            out.push(b'"');
            out.extend(t.iter().filter(|&&b| b != b'\n'));
            out.push(b'"');
        }
        2 => out.extend(t.iter().filter(|&&b| b != b'\n')),
        _ => {
            out.push(b'\'');
            out.extend(t.iter().filter(|&&b| b != b'\n'));
        }
    }
    out
}

fn scalar(s: &Scalar, out: &mut Vec<u8>) {
    match s {
        Scalar::Unicode(t, escape) => {
            out.push(b'V');
            for b in t.bytes() {
                match b {
                    b'\n' => out.extend_from_slice(b"\\u000a"),
                    b'\\' if *escape => out.extend_from_slice(b"\\u005c"),
                    _ => out.push(b),
                }
            }
        }
        Scalar::Str(t, how) => {
            out.push(b'S');
            out.extend(text_quoted(&t.bytes(), *how));
        }
        Scalar::Int(i) => out.extend_from_slice(format!("I{i}").as_bytes()),
        Scalar::Long(i) => out.extend_from_slice(format!("L{i}L").as_bytes()),
        Scalar::Float(f) => out.extend_from_slice(format!("F{f:?}").as_bytes()),
        Scalar::FloatText(t) => {
            out.push(b'F');
            out.extend(t.bytes().filter(|&b| b != b'\n'));
        }
        Scalar::None => {
            out.push(b'N');
            return;
        }
    }
    out.push(b'\n');
}

fn put(id: Option<u16>, out: &mut Vec<u8>) {
    if let Some(id) = id {
        out.extend_from_slice(format!("p{id}\n").as_bytes());
    }
}

fn op(o: &Op, out: &mut Vec<u8>) {
    let line = |out: &mut Vec<u8>, s: &str| {
        out.extend(s.bytes().filter(|&b| b != b'\n'));
        out.push(b'\n');
    };
    match o {
        Op::Mark => out.push(b'('),
        Op::Stop => out.push(b'.'),
        Op::Proto(v) => out.extend_from_slice(&[0x80, *v]),
        Op::BinUnicode(n, b) => {
            out.push(b'X');
            out.extend_from_slice(&n.to_le_bytes());
            out.extend_from_slice(b);
        }
        Op::ShortBinString(n, b) => {
            out.extend_from_slice(&[b'U', *n]);
            out.extend_from_slice(b);
        }
        Op::BinInt(i) => {
            out.push(b'J');
            out.extend_from_slice(&i.to_le_bytes());
        }
        Op::BinPut(i) => out.extend_from_slice(&[b'q', *i]),
        Op::BinGet(i) => out.extend_from_slice(&[b'h', *i]),
        Op::LongBinGet(i) => {
            out.push(b'j');
            out.extend_from_slice(&i.to_le_bytes());
        }
        Op::List => out.push(b'l'),
        Op::EmptyList => out.push(b']'),
        Op::Append => out.push(b'a'),
        Op::Appends => out.push(b'e'),
        Op::Tuple => out.push(b't'),
        Op::EmptyTuple => out.push(b')'),
        Op::Dict => out.push(b'd'),
        Op::EmptyDict => out.push(b'}'),
        Op::SetItem => out.push(b's'),
        Op::Global(m, n) => {
            out.push(b'c');
            line(out, m);
            line(out, n);
        }
        Op::Reduce => out.push(b'R'),
        Op::Build => out.push(b'b'),
        Op::Inst(m, n) => {
            out.push(b'i');
            line(out, m);
            line(out, n);
        }
        Op::Obj => out.push(b'o'),
        Op::Pop => out.push(b'0'),
        Op::Dup => out.push(b'2'),
        Op::Raw(b) => out.extend_from_slice(b),
    }
}

fn build(p: &Pickle) -> Vec<u8> {
    let mut out = Vec::new();
    match p.head % 4 {
        0 => out.extend_from_slice(b"(lp0\n"),
        1 => out.extend_from_slice(b"(l"),
        2 => out.extend_from_slice(b"\x80\x02]q\x00("),
        _ => {}
    }
    'outer: for _ in 0..=(p.repeat as usize % 128) {
        for (item, append) in &p.items {
            match item {
                Item::Scalar(s, id) => {
                    scalar(s, &mut out);
                    put(*id, &mut out);
                }
                Item::Tuple(parts, id) => {
                    out.push(b'(');
                    for part in parts {
                        match part {
                            Part::Scalar(s, id) => {
                                scalar(s, &mut out);
                                put(*id, &mut out);
                            }
                            Part::Get(id) => out.extend_from_slice(format!("g{id}\n").as_bytes()),
                        }
                    }
                    out.push(b't');
                    put(*id, &mut out);
                }
                Item::Get(id) => out.extend_from_slice(format!("g{id}\n").as_bytes()),
                Item::Op(o) => op(o, &mut out),
            }
            if *append {
                out.push(b'a');
            }
            if out.len() > SLOT {
                break 'outer;
            }
        }
    }
    match p.tail % 3 {
        0 => out.push(b'.'),
        1 => {}
        _ => {
            out.push(b'.');
            out.extend_from_slice(&p.trailing);
        }
    }
    out
}

fuzz_target!(|p: Pickle| {
    let pickle = build(&p);
    let at = slot();
    let mut file = SEED.to_vec();
    let n = pickle.len().min(SLOT);
    file[at..at + n].copy_from_slice(&pickle[..n]);
    file[at + n..at + SLOT].fill(0);
    let opts = ReadOptions {
        format: Some(Format::DeepLabCut),
        fps: Some(30.0),
        scale: Some(1.0),
        ..ReadOptions::default()
    };
    // FUZZ_WRITE=PATH: keep the built file (to reproduce an input with the CLI), and print
    // what reading it gave.
    let write = std::env::var_os("FUZZ_WRITE");
    if let Some(path) = &write {
        std::fs::write(path, &file).expect("write FUZZ_WRITE");
    }
    let read = read_recording_bytes(&file, std::path::Path::new("fuzz-input"), &opts);
    if write.is_some() {
        match read {
            Ok(r) => eprintln!("read: {} frames", r.len()),
            Err(e) => eprintln!("error: {e}"),
        }
    }
});
