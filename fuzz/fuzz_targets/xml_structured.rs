//! Structure-aware XML fuzzing: the input describes an element tree over the vocabularies of
//! Kinovea's spreadsheet (Excel 2003 XML: Workbook / Worksheet / Table / Row / Cell / Data,
//! `ss:` attributes, the export's row texts) and Tracker projects (`object class=...` /
//! `property name=... type=...`, frame data arrays `[n]`), with attributes repeated up to a few
//! thousand times, entities, CDATA, comments, deep nesting and numbers (huge, NaN, negative).
//! It is read as a Kinovea or a Tracker file: a recording or an error, never a panic.
#![no_main]

use appell::data::{read_recording_bytes, Format, ReadOptions};
use libfuzzer_sys::arbitrary::{self, Arbitrary};
use libfuzzer_sys::fuzz_target;

const MAX_BYTES: usize = 1_000_000;

#[derive(Arbitrary, Debug, Clone, Copy)]
enum Num {
    Int(i64),
    Small(i8),
    Float(f64),
    Nan,
    Inf,
    Huge,
    Exp(i16),
    Index(u32),
}

impl Num {
    fn text(self) -> String {
        match self {
            Num::Int(i) => i.to_string(),
            Num::Small(i) => format!("{}.{}", i / 10, (i % 10).abs()),
            Num::Float(f) => format!("{f:?}"),
            Num::Nan => "NaN".into(),
            Num::Inf => "-Infinity".into(),
            Num::Huge => "1e400".into(),
            Num::Exp(e) => format!("1.5e{e}"),
            Num::Index(i) => i.to_string(),
        }
    }
}

#[derive(Arbitrary, Debug)]
enum Text {
    Num(Num),
    /// Kinovea's time `h:mm:ss:cc`.
    Time(u16, u8, u8, u8),
    Word(u8),
    Entity(u8),
    CharRef(u32),
    Cdata(String),
    Comment(String),
    Any(String),
}

/// Words the readers look for.
const WORDS: [&str; 24] = [
    "Label :",
    "Coords (x,y:cm; t:time)",
    "Coords (x,y:m; t:time)",
    "Coords (x,y:mm; t:time)",
    "x",
    "y",
    "t",
    "slider",
    "bob",
    "",
    "m",
    "cm",
    "mm",
    "String",
    "Number",
    "org.opensourcephysics.cabrillo.tracker.TrackerPanel",
    "org.opensourcephysics.cabrillo.tracker.PointMass",
    "PointMass",
    "TrackerPanel",
    "VideoClip",
    "StepperClipControl",
    "ImageCoordSystem",
    "DynamicParticle",
    "frame",
];

const ELEMENTS: [&str; 16] = [
    "Workbook",
    "Worksheet",
    "Table",
    "Row",
    "Cell",
    "Data",
    "Styles",
    "Style",
    "ss:Data",
    "object",
    "property",
    "Column",
    "Names",
    "x:Row",
    "Font",
    "a",
];

const ATTRIBUTES: [&str; 16] = [
    "ss:Type",
    "ss:Index",
    "ss:Name",
    "ss:StyleID",
    "ss:MergeAcross",
    "ss:ExpandedRowCount",
    "xmlns",
    "xmlns:ss",
    "class",
    "name",
    "type",
    "x",
    "id",
    "ss:ID",
    "xml:space",
    "version",
];

const CLASSES: [&str; 12] = [
    "org.opensourcephysics.cabrillo.tracker.TrackerPanel",
    "org.opensourcephysics.cabrillo.tracker.PointMass",
    "org.opensourcephysics.media.core.VideoClip",
    "org.opensourcephysics.media.core.StepperClipControl",
    "org.opensourcephysics.media.core.ImageCoordSystem",
    "org.opensourcephysics.media.core.ImageCoordSystem$FrameData",
    "org.opensourcephysics.cabrillo.tracker.PointMass$FrameData",
    "org.opensourcephysics.cabrillo.tracker.DynamicParticle",
    "org.opensourcephysics.cabrillo.tracker.CenterOfMass",
    "org.opensourcephysics.cabrillo.tracker.Vector",
    "java.util.ArrayList",
    "",
];

const PROPERTIES: [&str; 20] = [
    "tracks",
    "framedata",
    "x",
    "y",
    "xorigin",
    "yorigin",
    "angle",
    "xscale",
    "yscale",
    "delta_t",
    "startframe",
    "length_unit",
    "name",
    "videoclip",
    "clipcontrol",
    "coords",
    "mass",
    "stepcount",
    "rate",
    "semantic_version",
];

#[derive(Arbitrary, Debug)]
enum AttrValue {
    Class(u8),
    Property(u8),
    /// `[n]`, an array element's index.
    Index(Num),
    Type(u8),
    Num(Num),
    Word(u8),
    Any(String),
}

#[derive(Arbitrary, Debug)]
struct Attr {
    name: u8,
    /// An arbitrary name instead (possibly not a valid XML name).
    any_name: Option<String>,
    value: AttrValue,
    /// Write this attribute (under numbered names) this many times (modulo 4,096).
    repeat: u16,
    single_quotes: bool,
}

#[derive(Arbitrary, Debug)]
enum Node {
    Element {
        name: u8,
        attrs: Vec<Attr>,
        children: Vec<Node>,
        /// Repeat this element this many times (modulo 256).
        repeat: u8,
        self_closing: bool,
    },
    Text(Text),
    /// An element nested this many levels deep (modulo 100,000), text at the bottom.
    Deep(u32, u8, Text),
    /// A closing tag that does not match, or other broken markup.
    Broken(String),
}

#[derive(Arbitrary, Debug)]
struct Doc {
    tracker: bool,
    /// The document's root element (Workbook or a TrackerPanel object) or any tree.
    root: bool,
    bom: bool,
    /// Give `--fps` (Kinovea numbers rows from it).
    fps: bool,
    doctype: Option<String>,
    nodes: Vec<Node>,
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('"', "&quot;")
        .replace('\'', "&apos;")
}

fn text(t: &Text, out: &mut String) {
    match t {
        Text::Num(n) => out.push_str(&n.text()),
        Text::Time(h, m, s, c) => out.push_str(&format!("{h}:{m:02}:{s:02}:{c:02}")),
        Text::Word(w) => out.push_str(&esc(WORDS[*w as usize % WORDS.len()])),
        Text::Entity(e) => out.push_str(
            [
                "&amp;", "&lt;", "&gt;", "&quot;", "&apos;", "&nbsp;", "&#0;", "&",
            ][*e as usize % 8],
        ),
        Text::CharRef(c) => out.push_str(&format!("&#x{c:x};")),
        Text::Cdata(s) => out.push_str(&format!("<![CDATA[{}]]>", s.replace("]]>", ""))),
        Text::Comment(s) => out.push_str(&format!("<!--{}-->", s.replace("--", ""))),
        Text::Any(s) => out.push_str(s),
    }
}

fn attr_value(v: &AttrValue) -> String {
    match v {
        AttrValue::Class(i) => CLASSES[*i as usize % CLASSES.len()].into(),
        AttrValue::Property(i) => PROPERTIES[*i as usize % PROPERTIES.len()].into(),
        AttrValue::Index(n) => format!("[{}]", n.text()),
        AttrValue::Type(i) => [
            "object", "array", "double", "int", "string", "boolean", "Number", "String",
        ][*i as usize % 8]
            .into(),
        AttrValue::Num(n) => n.text(),
        AttrValue::Word(w) => WORDS[*w as usize % WORDS.len()].into(),
        AttrValue::Any(s) => esc(s),
    }
}

fn node(n: &Node, out: &mut String, depth: usize) {
    if out.len() > MAX_BYTES {
        return;
    }
    match n {
        Node::Element {
            name,
            attrs,
            children,
            repeat,
            self_closing,
        } => {
            let name = ELEMENTS[*name as usize % ELEMENTS.len()];
            for _ in 0..=(*repeat as usize) {
                out.push('<');
                out.push_str(name);
                for a in attrs {
                    let an = match &a.any_name {
                        Some(s) => s.as_str(),
                        None => ATTRIBUTES[a.name as usize % ATTRIBUTES.len()],
                    };
                    let v = attr_value(&a.value);
                    let q = if a.single_quotes { '\'' } else { '"' };
                    for k in 0..=(a.repeat as usize % 4096) {
                        if k == 0 {
                            out.push_str(&format!(" {an}={q}{v}{q}"));
                        } else {
                            out.push_str(&format!(" {an}{k}={q}{v}{q}"));
                        }
                    }
                }
                if *self_closing {
                    out.push_str("/>");
                } else {
                    out.push('>');
                    if depth < 200 {
                        for c in children {
                            node(c, out, depth + 1);
                        }
                    }
                    out.push_str(&format!("</{name}>"));
                }
                if out.len() > MAX_BYTES {
                    return;
                }
            }
        }
        Node::Text(t) => text(t, out),
        Node::Deep(n, name, t) => {
            let name = ELEMENTS[*name as usize % ELEMENTS.len()];
            let n = *n as usize % 100_000;
            for _ in 0..n {
                out.push_str(&format!("<{name}>"));
            }
            text(t, out);
            for _ in 0..n {
                out.push_str(&format!("</{name}>"));
            }
        }
        Node::Broken(s) => out.push_str(s),
    }
}

fn build(d: &Doc) -> String {
    let mut out = String::new();
    if d.bom {
        out.push('\u{feff}');
    }
    out.push_str("<?xml version=\"1.0\" encoding=\"UTF-8\"?>");
    if let Some(dt) = &d.doctype {
        out.push_str(&format!("<!DOCTYPE {dt}>"));
    }
    if d.tracker {
        if d.root {
            out.push_str(
                "\n<object class=\"org.opensourcephysics.cabrillo.tracker.TrackerPanel\">\n",
            );
        }
    } else {
        out.push_str("<?mso-application progid=\"Excel.Sheet\"?>");
        if d.root {
            out.push_str("<Workbook xmlns=\"urn:schemas-microsoft-com:office:spreadsheet\" xmlns:ss=\"urn:schemas-microsoft-com:office:spreadsheet\">\n");
        }
    }
    for n in &d.nodes {
        node(n, &mut out, 0);
    }
    if d.root {
        out.push_str(if d.tracker {
            "</object>"
        } else {
            "</Workbook>"
        });
    }
    out
}

fuzz_target!(|d: Doc| {
    let text = build(&d);
    let opts = ReadOptions {
        format: Some(if d.tracker {
            Format::Tracker
        } else {
            Format::Kinovea
        }),
        fps: d.fps.then_some(30.0),
        scale: Some(1.0),
        ..ReadOptions::default()
    };
    // FUZZ_WRITE=PATH: keep the built file (to reproduce an input with the CLI), and print
    // what reading it gave.
    let write = std::env::var_os("FUZZ_WRITE");
    if let Some(path) = &write {
        std::fs::write(path, text.as_bytes()).expect("write FUZZ_WRITE");
    }
    let read = read_recording_bytes(text.as_bytes(), std::path::Path::new("fuzz-input"), &opts);
    if write.is_some() {
        match read {
            Ok(r) => eprintln!("read: {} frames", r.len()),
            Err(e) => eprintln!("error: {e}"),
        }
    }
});
