//! Structure-aware HDF5 fuzzing by targeted mutation: each seed (the repo's SLEAP and
//! DeepLabCut files, the budget files and h5py-made SLEAP files with chunking, deflate,
//! shuffle, Fletcher-32, scale-offset and LZF, `fuzz/seeds/`) is parsed once (superblock v0,
//! v1 object headers and their continuations, symbol-table groups through their B-trees and
//! symbol nodes, chunk B-trees, local heaps) into a list of fields; the input picks a seed,
//! the format to read it as, and mutations that overwrite those fields (dataspace dimensions,
//! datatype class and size, layout class, chunk dimensions and addresses, filter ids and
//! parameters, attribute sizes, message sizes, B-tree entry counts and children, heap sizes)
//! with chosen values. The file then goes to the reader: a recording or an error, never a
//! panic.
#![no_main]

use appell::data::{read_recording_bytes, Format, ReadOptions};
use libfuzzer_sys::arbitrary::{self, Arbitrary};
use libfuzzer_sys::fuzz_target;
use std::sync::OnceLock;

const SEEDS: [&[u8]; 16] = [
    include_bytes!("../../tests/data/DERIVED_dlc_coords_x_y_speed.h5"),
    include_bytes!("../../tests/data/dlc_labeled_CollectedData_Mackenzie.h5"),
    include_bytes!("../../tests/data/dlc_labeled_CollectedData_Mackenzie_fixed.h5"),
    include_bytes!("../../tests/data/dlc_movementdata_mouse_multi_4row.h5"),
    include_bytes!("../../tests/data/dlc_reachingvideo1shortDLC_resnet50_TESTNov4shuffle1_10.h5"),
    include_bytes!("../../tests/data/sleap_three-mice_Aeon.analysis.h5"),
    include_bytes!("../../tests/data/budget/dlc_fixed_1e8_codes.h5"),
    include_bytes!("../../tests/data/budget/dlc_fixed_1e8_columns.h5"),
    include_bytes!("../../tests/data/budget/sleap_1e9_nodes.h5"),
    include_bytes!("../../tests/data/budget/sleap_scaleoffset_1gib.h5"),
    include_bytes!("../seeds/sleap_chunk_fletcher_f8.h5"),
    include_bytes!("../seeds/sleap_chunk_gzip_shuffle.h5"),
    include_bytes!("../seeds/sleap_contig_f4.h5"),
    include_bytes!("../seeds/sleap_lzf.h5"),
    include_bytes!("../seeds/sleap_scaleoffset.h5"),
    include_bytes!("../seeds/sleap_vlen_names.h5"),
];

/// What a field is, for the mutations that target one kind.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    /// A dataspace's rank, a dimension or a maximum dimension.
    Rank,
    Dim,
    /// A datatype's class-and-version byte, its size, a compound member's offset.
    TypeClass,
    TypeSize,
    MemberOffset,
    /// A layout's class, data address and size, a chunk dimension.
    LayoutClass,
    Address,
    Length,
    ChunkDim,
    /// A filter's id, its client-data count, a client-data value; the number of filters.
    FilterId,
    FilterCount,
    FilterValue,
    /// Attribute name / datatype / dataspace sizes.
    AttrSize,
    /// A header message's type and size; the header's message count and size.
    MsgType,
    MsgSize,
    HeaderCount,
    /// B-tree node: entries used, level, a chunk key's size or offset; symbol node count.
    Entries,
    Level,
    ChunkKey,
    /// A byte inside a message's body or a chunk.
    Body,
}

#[derive(Clone, Copy, Debug)]
struct Field {
    at: usize,
    width: usize,
    kind: Kind,
}

struct Walk<'a> {
    d: &'a [u8],
    fields: Vec<Field>,
    seen: Vec<usize>,
}

impl Walk<'_> {
    fn u(&self, at: usize, w: usize) -> Option<u64> {
        let b = self.d.get(at..at.checked_add(w)?)?;
        Some(b.iter().rev().fold(0u64, |a, &x| a << 8 | x as u64))
    }
    fn f(&mut self, at: usize, width: usize, kind: Kind) {
        if at + width <= self.d.len() {
            self.fields.push(Field { at, width, kind });
        }
    }
    fn visit(&mut self, addr: u64) -> bool {
        let a = addr as usize;
        if addr == u64::MAX
            || a >= self.d.len()
            || self.seen.contains(&a)
            || self.seen.len() > 10_000
        {
            return false;
        }
        self.seen.push(a);
        true
    }

    /// A v1 object header at `addr`.
    fn header(&mut self, addr: u64) {
        if !self.visit(addr) || self.u(addr as usize, 1) != Some(1) {
            return;
        }
        let a = addr as usize;
        self.f(a + 2, 2, Kind::HeaderCount);
        self.f(a + 8, 4, Kind::MsgSize);
        let Some(size) = self.u(a + 8, 4) else { return };
        let mut blocks = vec![(a + 16, size as usize)];
        while let Some((start, len)) = blocks.pop() {
            let mut p = start;
            while p + 8 <= start + len && p + 8 <= self.d.len() && self.fields.len() < 100_000 {
                let (Some(ty), Some(sz)) = (self.u(p, 2), self.u(p + 2, 2)) else {
                    break;
                };
                self.f(p, 2, Kind::MsgType);
                self.f(p + 2, 2, Kind::MsgSize);
                let body = p + 8;
                let sz = sz as usize;
                if body + sz > self.d.len() {
                    break;
                }
                for k in (0..sz).step_by(4) {
                    self.f(body + k, 1, Kind::Body);
                }
                match ty {
                    0x01 => self.dataspace(body),
                    0x03 => self.datatype(body, sz),
                    0x08 => self.layout(body),
                    0x0B => self.filters(body, sz),
                    0x0C => self.attribute(body),
                    0x10 => {
                        if let (Some(ca), Some(cl)) = (self.u(body, 8), self.u(body + 8, 8)) {
                            self.f(body, 8, Kind::Address);
                            self.f(body + 8, 8, Kind::Length);
                            if self.visit(ca) {
                                blocks.push((ca as usize, cl as usize));
                            }
                        }
                    }
                    0x11 => {
                        if let (Some(bt), Some(heap)) = (self.u(body, 8), self.u(body + 8, 8)) {
                            self.f(body, 8, Kind::Address);
                            self.f(body + 8, 8, Kind::Address);
                            self.heap(heap);
                            self.btree(bt, 0);
                        }
                    }
                    _ => {}
                }
                p = body + sz;
            }
        }
    }

    fn dataspace(&mut self, b: usize) {
        let (Some(ver), Some(rank), Some(flags)) =
            (self.u(b, 1), self.u(b + 1, 1), self.u(b + 2, 1))
        else {
            return;
        };
        self.f(b + 1, 1, Kind::Rank);
        let dims = if ver == 1 { b + 8 } else { b + 4 };
        let n = rank as usize * if flags & 1 != 0 { 2 } else { 1 };
        for k in 0..n {
            self.f(dims + 8 * k, 8, Kind::Dim);
        }
    }

    fn datatype(&mut self, b: usize, sz: usize) {
        self.f(b, 1, Kind::TypeClass);
        self.f(b + 4, 4, Kind::TypeSize);
        // Compound members (class 6): name, offset; look for nested sizes heuristically.
        if self.u(b, 1).map(|c| c & 0x0f) == Some(6) {
            let mut p = b + 8;
            while p + 8 < b + sz {
                let Some(name_end) = self
                    .d
                    .get(p..b + sz)
                    .and_then(|s| s.iter().position(|&c| c == 0))
                    .map(|k| p + k)
                else {
                    break;
                };
                let off = if self.u(b, 1).map(|c| c >> 4) == Some(3) {
                    name_end + 1
                } else {
                    (name_end + 1).next_multiple_of(8).max(p)
                };
                self.f(off, 4, Kind::MemberOffset);
                self.f(off + 4, 4, Kind::TypeSize);
                p = off + 8;
            }
        }
    }

    fn layout(&mut self, b: usize) {
        if self.u(b, 1) != Some(3) {
            return;
        }
        self.f(b + 1, 1, Kind::LayoutClass);
        match self.u(b + 1, 1) {
            Some(1) => {
                self.f(b + 2, 8, Kind::Address);
                self.f(b + 10, 8, Kind::Length);
            }
            Some(2) => {
                let Some(nd) = self.u(b + 2, 1) else { return };
                self.f(b + 2, 1, Kind::Rank);
                if let Some(bt) = self.u(b + 3, 8) {
                    self.f(b + 3, 8, Kind::Address);
                    self.btree(bt, nd as usize);
                }
                for k in 0..nd as usize {
                    self.f(b + 11 + 4 * k, 4, Kind::ChunkDim);
                }
            }
            Some(0) => self.f(b + 2, 2, Kind::Length),
            _ => {}
        }
    }

    fn filters(&mut self, b: usize, sz: usize) {
        let Some(ver) = self.u(b, 1) else { return };
        self.f(b + 1, 1, Kind::FilterCount);
        let n = self.u(b + 1, 1).unwrap_or(0);
        let mut p = if ver == 1 { b + 8 } else { b + 2 };
        for _ in 0..n {
            if p + 8 > b + sz {
                return;
            }
            let Some(id) = self.u(p, 2) else { return };
            self.f(p, 2, Kind::FilterId);
            let (name_len, ncd_at) = if ver == 1 || id >= 256 {
                (self.u(p + 2, 2).unwrap_or(0) as usize, p + 6)
            } else {
                (0, p + 4)
            };
            self.f(ncd_at, 2, Kind::FilterCount);
            let ncd = self.u(ncd_at, 2).unwrap_or(0) as usize;
            let mut cd = ncd_at
                + 2
                + if ver == 1 {
                    name_len.next_multiple_of(8)
                } else {
                    name_len
                };
            for _ in 0..ncd {
                self.f(cd, 4, Kind::FilterValue);
                cd += 4;
            }
            if ver == 1 && ncd % 2 == 1 {
                cd += 4;
            }
            p = cd;
        }
    }

    fn attribute(&mut self, b: usize) {
        let Some(ver) = self.u(b, 1) else { return };
        let (name_at, pad) = match ver {
            1 => (b + 8, true),
            2 => (b + 8, false),
            3 => (b + 9, false),
            _ => return,
        };
        let size_at = if ver == 3 { b + 2 } else { b + 2 };
        for k in 0..3 {
            self.f(size_at + 2 * k, 2, Kind::AttrSize);
        }
        let (Some(nl), Some(tl)) = (self.u(size_at, 2), self.u(size_at + 2, 2)) else {
            return;
        };
        let al = |n: u64| if pad { n.next_multiple_of(8) } else { n } as usize;
        let ty = name_at + al(nl);
        let sp = ty + al(tl);
        self.datatype(ty, tl as usize);
        self.dataspace(sp);
    }

    fn heap(&mut self, addr: u64) {
        let a = addr as usize;
        if self.d.get(a..a + 4) == Some(b"HEAP") {
            self.f(a + 8, 8, Kind::Length);
            self.f(a + 16, 8, Kind::Length);
            self.f(a + 24, 8, Kind::Address);
        }
    }

    /// A v1 B-tree node: group nodes (type 0) lead to symbol nodes, chunk nodes (type 1,
    /// `nd` chunk dimensions) to chunks.
    fn btree(&mut self, addr: u64, nd: usize) {
        if !self.visit(addr) {
            return;
        }
        let a = addr as usize;
        if self.d.get(a..a + 4) != Some(b"TREE") {
            return;
        }
        let (Some(ty), Some(level), Some(used)) =
            (self.u(a + 4, 1), self.u(a + 5, 1), self.u(a + 6, 2))
        else {
            return;
        };
        self.f(a + 5, 1, Kind::Level);
        self.f(a + 6, 2, Kind::Entries);
        self.f(a + 8, 8, Kind::Address);
        self.f(a + 16, 8, Kind::Address);
        let key = if ty == 0 { 8 } else { 8 + 8 * nd };
        let mut p = a + 24;
        for _ in 0..used.min(1000) {
            if ty == 1 {
                self.f(p, 4, Kind::ChunkKey);
                for k in 0..nd {
                    self.f(p + 8 + 8 * k, 8, Kind::ChunkKey);
                }
            }
            p += key;
            self.f(p, 8, Kind::Address);
            let Some(child) = self.u(p, 8) else { return };
            p += 8;
            if level > 0 {
                self.btree(child, nd);
            } else if ty == 0 {
                self.symbols(child);
            } else if let Some(size) = self.u(p - 8 - key, 4) {
                // The chunk's bytes.
                let c = child as usize;
                for k in (0..size as usize).step_by(7).take(64) {
                    self.f(c + k, 1, Kind::Body);
                }
            }
        }
    }

    fn symbols(&mut self, addr: u64) {
        if !self.visit(addr) {
            return;
        }
        let a = addr as usize;
        if self.d.get(a..a + 4) != Some(b"SNOD") {
            return;
        }
        self.f(a + 6, 2, Kind::Entries);
        let n = self.u(a + 6, 2).unwrap_or(0);
        for k in 0..n as usize {
            let e = a + 8 + 40 * k;
            self.f(e, 8, Kind::Length);
            self.f(e + 8, 8, Kind::Address);
            if let Some(oh) = self.u(e + 8, 8) {
                self.header(oh);
            }
        }
    }
}

fn fields(seed: usize) -> &'static [Field] {
    static F: OnceLock<Vec<Vec<Field>>> = OnceLock::new();
    &F.get_or_init(|| {
        SEEDS
            .iter()
            .map(|d| {
                let mut w = Walk {
                    d,
                    fields: Vec::new(),
                    seen: Vec::new(),
                };
                if d.get(8) == Some(&0) {
                    if let Some(root) = w.u(64, 8) {
                        w.f(64, 8, Kind::Address);
                        w.f(40, 8, Kind::Length);
                        w.header(root);
                    }
                }
                if std::env::var_os("HDF5_FUZZ_FIELDS").is_some() {
                    let count = |k: Kind| w.fields.iter().filter(|f| f.kind == k).count();
                    let counts: Vec<_> = KINDS[..20].iter().map(|&k| (k, count(k))).collect();
                    eprintln!("seed of {} bytes: {counts:?}", d.len());
                }
                w.fields
            })
            .collect::<Vec<_>>()
    })[seed]
}

#[derive(Arbitrary, Debug, Clone, Copy)]
enum Value {
    Zero,
    One,
    Two,
    Max,
    /// All ones in the field's width minus a little.
    NearMax(u8),
    Pow2(u8),
    Small(u8),
    Add(i16),
    Any(u64),
    /// A filter id: deflate, shuffle, Fletcher-32, szip, n-bit, scale-offset, LZF, unknown.
    Filter(u8),
    /// A datatype class (low nibble) with version 1..3.
    Class(u8, u8),
    /// Offset of another field of the file.
    FieldAt(u16),
}

#[derive(Arbitrary, Debug)]
struct Mutation {
    /// Which kind of field (modulo the kinds present), then which one of that kind.
    kind: u8,
    index: u16,
    value: Value,
}

#[derive(Arbitrary, Debug)]
struct Input {
    seed: u8,
    /// Read as SLEAP, DeepLabCut, or by detection.
    format: u8,
    fps: bool,
    mutations: Vec<Mutation>,
    /// Cut the file after this many bytes.
    truncate: Option<u32>,
}

const KINDS: [Kind; 21] = [
    Kind::Rank,
    Kind::Dim,
    Kind::TypeClass,
    Kind::TypeSize,
    Kind::MemberOffset,
    Kind::LayoutClass,
    Kind::Address,
    Kind::Length,
    Kind::ChunkDim,
    Kind::FilterId,
    Kind::FilterCount,
    Kind::FilterValue,
    Kind::AttrSize,
    Kind::MsgType,
    Kind::MsgSize,
    Kind::HeaderCount,
    Kind::Entries,
    Kind::Level,
    Kind::ChunkKey,
    Kind::Body,
    Kind::Dim,
];

fn apply(file: &mut [u8], fields: &[Field], m: &Mutation) {
    let kind = KINDS[m.kind as usize % KINDS.len()];
    let of_kind: Vec<&Field> = fields.iter().filter(|f| f.kind == kind).collect();
    if of_kind.is_empty() {
        return;
    }
    let f = of_kind[m.index as usize % of_kind.len()];
    let w = f.width;
    let mask = if w >= 8 {
        u64::MAX
    } else {
        (1u64 << (8 * w)) - 1
    };
    let old = file[f.at..f.at + w]
        .iter()
        .rev()
        .fold(0u64, |a, &x| a << 8 | x as u64);
    let v = match m.value {
        Value::Zero => 0,
        Value::One => 1,
        Value::Two => 2,
        Value::Max => mask,
        Value::NearMax(d) => mask - d as u64 % 16,
        Value::Pow2(p) => 1u64.checked_shl(p as u32 % 64).unwrap_or(0),
        Value::Small(s) => s as u64,
        Value::Add(d) => old.wrapping_add(d as i64 as u64),
        Value::Any(v) => v,
        Value::Filter(i) => [1, 2, 3, 4, 5, 6, 32000, 32001, 307, 0][i as usize % 10],
        Value::Class(c, v) => ((v as u64 % 3 + 1) << 4) | (c as u64 % 11),
        Value::FieldAt(i) => fields[i as usize % fields.len()].at as u64,
    } & mask;
    file[f.at..f.at + w].copy_from_slice(&v.to_le_bytes()[..w]);
}

fuzz_target!(|input: Input| {
    let seed = input.seed as usize % SEEDS.len();
    let mut file = SEEDS[seed].to_vec();
    let fields = fields(seed);
    for m in input.mutations.iter().take(32) {
        apply(&mut file, fields, m);
    }
    if let Some(n) = input.truncate {
        file.truncate(n as usize);
    }
    let format = match input.format % 3 {
        0 => Some(Format::Sleap),
        1 => Some(Format::DeepLabCut),
        _ => None,
    };
    let opts = ReadOptions {
        format,
        fps: input.fps.then_some(30.0),
        scale: Some(1.0),
        ..ReadOptions::default()
    };
    // FUZZ_WRITE=PATH: keep the built file (to reproduce an input with the CLI), and print
    // what reading it gave.
    let write = std::env::var_os("FUZZ_WRITE");
    if let Some(path) = &write {
        std::fs::write(path, &file).expect("write FUZZ_WRITE");
    }
    let read = read_recording_bytes(&file, std::path::Path::new("fuzz-input.h5"), &opts);
    if write.is_some() {
        match read {
            Ok(r) => eprintln!("read: {} frames", r.len()),
            Err(e) => eprintln!("error: {e}"),
        }
    }
});
