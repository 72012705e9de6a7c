//! The architecture of `src/`, read from the sources (issue 62, item 5). Two rules:
//!
//! - Layers. No module imports one above it in [`LAYERS`], listed bottom first: `output.rs` and
//!   `cpu.rs`, then `model/`, `sim/`, `scene.rs`, `data/`, `fit/`, `plan/`, `report/`,
//!   `pipeline/`, `bench/` (`bench.rs` with its folder), and the binary (`main.rs`, `cli/`) on
//!   top. `lib.rs` only declares the modules and is exempt. An import allowed upward sits in
//!   [`UPWARD_EXCEPTIONS`] with its reason; an exception that matches no import any more fails
//!   the test too, so the list only shrinks.
//! - No loops. Inside one layer (a top-level folder with all its subfolders; the bottom layer's
//!   two files together) no file imports a file that imports it, directly or around a longer
//!   loop. Each `.rs` file is a node and a `mod.rs` (or `bench.rs`) is its folder's face: a
//!   `mod` declaration is not an import, but a `use` in it (`pub use` included) is. So a face
//!   that re-exports from a child and a child that takes an item from its face form a loop:
//!   the vocabulary the children share belongs in a file below them, not in the face. A loop
//!   allowed for now sits in [`LOOP_EXCEPTIONS`] by its folder, with its size and reason; a
//!   loop that grows past its size, or an exception without its loop, fails the test.
//!
//! Scene's place. `scene.rs` builds the simulator's `Request` and `Options` from a scene file
//! (it imports `sim` as well as `model`), so it cannot stand beside `model`; `data/synth.rs`
//! synthesises recordings from a `Scene`, so it must stand below `data`. It sits between `sim`
//! and `data`. The parameters' names it takes (`Param`) live with the model, below it.
//!
//! What counts as an import, file by file:
//! - every leaf of a `use` tree (`pub use` too), groups expanded: `use crate::fit::{a, b::{c,
//!   d}}` is `crate::fit::a`, `crate::fit::b::c` and `crate::fit::b::d`; `self` in a group is
//!   the group's own path;
//! - every path written in code that starts with `crate::` (`$crate::` in a macro), `super::`
//!   (repeated: `super::super::`), `self::`, the name of a child module the file declares
//!   (`forward::run(..)` in the face of `forward.rs`), a module name a `use` brought in, or, in
//!   the binary, `appell::`;
//! - a path is resolved segment by segment to the deepest module file that exists,
//!   `src/a/b.rs` or `src/a/b/mod.rs`: `crate::fit::select::forward::run` is
//!   `src/fit/select/forward.rs`, and `crate::fit::FitReport` (an item defined or re-exported
//!   by the face) is `src/fit/mod.rs`. The last segment of a path in code names an item, never
//!   a module, and so does the last of a `use` where the module of that name is private to
//!   another folder: `select::forward(..)` outside `select/` calls the function
//!   `fit/select/mod.rs` re-exports, so it reaches the face, not `forward.rs`. Paths to
//!   `lib.rs` and a file's paths to itself are no edge.
//!
//! Not read: comments (`//`, `///`, `//!`, `/* */`), string, raw-string and char literals,
//! and every item under a `#[cfg(..)]` that needs `test` (a `mod tests { .. }` block, a test
//! helper, a test module in its own file such as `sim/hybrid/tests.rs`): test code may import
//! freely. `tests/` and `python/` are outside the rules. A module inside a file (`mod x { .. }`)
//! is read as part of its file.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt;
use std::path::Path;

/// The layers of `src/`, bottom first, by top-level module (`cli` stands for the binary:
/// `main.rs` and `cli/`). A file may import its own layer and the layers below it.
const LAYERS: [&[&str]; 11] = [
    &["output", "cpu", "numbers"],
    &["model"],
    &["sim"],
    &["scene"],
    &["data"],
    &["fit"],
    &["plan"],
    &["report"],
    &["pipeline"],
    &["bench"],
    &["cli"],
];

/// An import allowed to run upward: the importing file (relative to `src/`), the path it
/// imports as resolved (`crate::` and the path; a longer path under it matches too) and why.
struct Exception {
    file: &'static str,
    path: &'static str,
    reason: &'static str,
}

/// The imports allowed upward: none (the fit hands the report numbers, and `report/` words
/// them; scenes take the parameters' names from the model).
const UPWARD_EXCEPTIONS: [Exception; 0] = [];

/// A loop allowed for now: the deepest folder holding all its files, the most files it may
/// hold (a loop that grows fails) and why.
struct LoopException {
    folder: &'static str,
    files: usize,
    reason: &'static str,
}

/// The loops allowed for now. In most folders the only loop is the face's (the face re-exports
/// its children and they take the shared vocabulary back from it); the reason says where files
/// also call each other in a loop. `fit/` and its folders have none: their vocabulary sits in
/// files below the stages (settings, estimates, outcomes, errors), and each face only lists
/// its modules and what it offers.
const LOOP_EXCEPTIONS: [LoopException; 8] = [
    LoopException {
        folder: "model/",
        files: 5,
        reason: "the face only: model/mod.rs re-exports forces, markers, rig and transition, \
                 which take `Mode`, `State`, `Scalar` and the indices from it",
    },
    LoopException {
        folder: "sim/",
        files: 7,
        reason: "the faces (hybrid/ takes `Options`, `Solution`, `Run`, `Segment` from sim/mod.rs \
                 and hybrid/mod.rs), and hybrid/'s guards, locate and step call each other",
    },
    LoopException {
        folder: "data/",
        files: 34,
        reason: "the faces (the readers take `DataError`, `Parsed`, `ReadOptions` from \
                 data/mod.rs, mcap's files `Reading`, `Step` from mcap/mod.rs), and \
                 mcap/decode/mod.rs and mcap/tf.rs take from each other",
    },
    LoopException {
        folder: "data/inspect/",
        files: 3,
        reason: "the face only: advice and pairs take `sig`, `Inspection` and the limits from \
                 inspect/mod.rs",
    },
    LoopException {
        folder: "plan/",
        files: 2,
        reason: "two loops of two files: plan/prior.rs takes `PlanSpec` and `Uncertain` from \
                 plan/spec.rs, which takes `Prior` back; plan/discriminate.rs judges releases \
                 through search.rs's `Evaluator`, which holds the `Laws` it weighs (the laws' \
                 vocabulary, `Law` and `LawTable`, sits below both in plan/law.rs)",
    },
    LoopException {
        folder: "report/fit/",
        files: 2,
        reason: "the face only: text.rs takes `answer` and `correlated_pairs` from \
                 report/fit/mod.rs",
    },
    LoopException {
        folder: "report/regions/",
        files: 2,
        reason: "the face only: figure.rs takes `Trajectory` from report/regions/mod.rs",
    },
    LoopException {
        folder: "cli/",
        files: 9,
        reason: "the face only: every command takes `Failure` (and `refuse_input`) from \
                 cli/mod.rs",
    },
];

/// The source files by their path relative to `src/` (`fit/select/mod.rs`), with their text.
type Files = BTreeMap<String, String>;

/// `src/` read whole.
fn read_src() -> Files {
    let root = Path::new(option_env!("CARGO_MANIFEST_DIR").unwrap_or(".")).join("src");
    let mut files = Files::new();
    read_dir(&root, "", &mut files);
    files
}

fn read_dir(dir: &Path, prefix: &str, files: &mut Files) {
    let entries = std::fs::read_dir(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    for entry in entries {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        if path.is_dir() {
            read_dir(&path, &format!("{prefix}{name}/"), files);
        } else if name.ends_with(".rs") {
            let text = std::fs::read_to_string(&path).unwrap();
            files.insert(format!("{prefix}{name}"), text);
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Tokens: the source without its comments and literals.

#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Ident(String),
    /// `::`
    Sep,
    Punct(char),
}

#[derive(Clone, Debug)]
struct Token {
    tok: Tok,
    line: usize,
}

impl Token {
    fn ident(&self) -> Option<&str> {
        match &self.tok {
            Tok::Ident(s) => Some(s),
            _ => None,
        }
    }

    fn is(&self, c: char) -> bool {
        self.tok == Tok::Punct(c)
    }
}

/// Identifiers, `::` and single punctuation with their lines. Comments, strings (also raw and
/// byte strings), char literals, numbers and `$` are dropped; a lifetime leaves its name.
fn tokenize(src: &str) -> Vec<Token> {
    let chars: Vec<char> = src.chars().collect();
    let mut out = Vec::new();
    let mut line = 1;
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        let next = chars.get(i + 1).copied();
        if c == '\n' {
            line += 1;
            i += 1;
        } else if c.is_whitespace() {
            i += 1;
        } else if c == '/' && next == Some('/') {
            while i < chars.len() && chars[i] != '\n' {
                i += 1;
            }
        } else if c == '/' && next == Some('*') {
            i = skip_block_comment(&chars, i, &mut line);
        } else if c == '"' {
            i = skip_string(&chars, i + 1, &mut line);
        } else if c == '\'' {
            i = skip_quote(&chars, i);
        } else if c.is_ascii_digit() {
            while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
        } else if c.is_alphabetic() || c == '_' {
            let start = i;
            while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            let word: String = chars[start..i].iter().collect();
            match (word.as_str(), chars.get(i)) {
                ("b" | "c", Some('"')) => i = skip_string(&chars, i + 1, &mut line),
                ("b", Some('\'')) => i = skip_quote(&chars, i),
                ("r" | "br" | "cr", Some('"' | '#')) => {
                    let mut j = i;
                    while chars.get(j) == Some(&'#') {
                        j += 1;
                    }
                    if chars.get(j) == Some(&'"') {
                        i = skip_raw_string(&chars, j + 1, j - i, &mut line);
                    } else {
                        // A raw identifier (`r#type`): its name follows.
                        i = j;
                    }
                }
                _ => out.push(Token {
                    tok: Tok::Ident(word),
                    line,
                }),
            }
        } else if c == '$' {
            // A macro's `$crate` is `crate`; a metavariable `$x` leaves its name.
            i += 1;
        } else if c == ':' && next == Some(':') {
            out.push(Token {
                tok: Tok::Sep,
                line,
            });
            i += 2;
        } else {
            out.push(Token {
                tok: Tok::Punct(c),
                line,
            });
            i += 1;
        }
    }
    out
}

/// Past a `/* .. */` comment starting at `i` (nested ones included).
fn skip_block_comment(chars: &[char], mut i: usize, line: &mut usize) -> usize {
    let mut depth = 0;
    while i < chars.len() {
        if chars[i] == '/' && chars.get(i + 1) == Some(&'*') {
            depth += 1;
            i += 2;
        } else if chars[i] == '*' && chars.get(i + 1) == Some(&'/') {
            depth -= 1;
            i += 2;
            if depth == 0 {
                break;
            }
        } else {
            if chars[i] == '\n' {
                *line += 1;
            }
            i += 1;
        }
    }
    i
}

/// Past the closing quote of a string whose text starts at `i`.
fn skip_string(chars: &[char], mut i: usize, line: &mut usize) -> usize {
    while i < chars.len() {
        match chars[i] {
            '"' => return i + 1,
            '\\' => {
                if chars.get(i + 1) == Some(&'\n') {
                    *line += 1;
                }
                i += 2;
            }
            '\n' => {
                *line += 1;
                i += 1;
            }
            _ => i += 1,
        }
    }
    i
}

/// Past the end of a raw string (`"` and `hashes` times `#`) whose text starts at `i`.
fn skip_raw_string(chars: &[char], mut i: usize, hashes: usize, line: &mut usize) -> usize {
    while i < chars.len() {
        if chars[i] == '"' && (1..=hashes).all(|k| chars.get(i + k) == Some(&'#')) {
            return i + 1 + hashes;
        }
        if chars[i] == '\n' {
            *line += 1;
        }
        i += 1;
    }
    i
}

/// Past a char literal (`'{'`, `'\''`, `'\u{7f}'`) starting at `i`, or past the quote of a
/// lifetime or label (`'a`), whose name is then read as an identifier.
fn skip_quote(chars: &[char], i: usize) -> usize {
    if chars.get(i + 1) == Some(&'\\') {
        let mut j = i + 3;
        while j < chars.len() && chars[j] != '\'' {
            j += 1;
        }
        j + 1
    } else if chars.get(i + 2) == Some(&'\'') {
        i + 3
    } else {
        i + 1
    }
}

// ---------------------------------------------------------------------------------------------
// Test code: items under a cfg that needs `test` are dropped.

/// The index past an attribute `#[..]` starting at `i`, if one does.
fn attribute_end(toks: &[Token], i: usize) -> Option<usize> {
    if !(toks.get(i)?.is('#') && toks.get(i + 1)?.is('[')) {
        return None;
    }
    let mut depth = 0;
    for (k, t) in toks.iter().enumerate().skip(i + 1) {
        if t.is('[') {
            depth += 1;
        } else if t.is(']') {
            depth -= 1;
            if depth == 0 {
                return Some(k + 1);
            }
        }
    }
    None
}

/// The index past a `#[cfg(..)]` at `i` that needs `test` (`test`, `all(test, ..)`, not
/// `not(test)`), if one starts there.
fn test_attribute_end(toks: &[Token], i: usize) -> Option<usize> {
    let end = attribute_end(toks, i)?;
    let words: Vec<&str> = toks[i + 2..end - 1]
        .iter()
        .filter_map(Token::ident)
        .collect();
    (words.first() == Some(&"cfg") && words.contains(&"test") && !words.contains(&"not"))
        .then_some(end)
}

/// Words that start an item whose own generics (`<A, B>`) may hold a comma at depth 0; a field,
/// an argument or a statement under the attribute ends at its comma instead.
const ITEM_WORDS: [&str; 13] = [
    "fn", "impl", "struct", "enum", "mod", "use", "const", "static", "trait", "type", "unsafe",
    "async", "extern",
];

/// The index past the item starting at `i` (a `;`- or `{ .. }`-ended item, or a field, argument
/// or statement ended by `,`), and the module's name if the item is `mod name;`.
fn item_end(toks: &[Token], i: usize) -> (usize, Option<String>) {
    let mut k = i;
    if toks.get(k).and_then(Token::ident) == Some("pub") {
        k += 1;
        if toks.get(k).is_some_and(|t| t.is('(')) {
            while k < toks.len() && !toks[k].is(')') {
                k += 1;
            }
            k += 1;
        }
    }
    let first = toks.get(k).and_then(Token::ident);
    let module = match (first, toks.get(k + 1), toks.get(k + 2)) {
        (Some("mod"), Some(name), Some(semi)) if semi.is(';') => name.ident().map(str::to_owned),
        _ => None,
    };
    let comma_ends = !first.is_some_and(|w| ITEM_WORDS.contains(&w));
    let mut depth = 0;
    for (k, t) in toks.iter().enumerate().skip(i) {
        match t.tok {
            Tok::Punct('(' | '[' | '{') => depth += 1,
            Tok::Punct(c @ (')' | ']' | '}')) => {
                if depth == 0 {
                    // The closer of what holds the item: the item ended before it.
                    return (k, module);
                }
                depth -= 1;
                if depth == 0 && c == '}' {
                    return (k + 1, module);
                }
            }
            Tok::Punct(';') if depth == 0 => return (k + 1, module),
            Tok::Punct(',') if depth == 0 && comma_ends => return (k + 1, module),
            _ => {}
        }
    }
    (toks.len(), module)
}

/// The tokens outside test code, and the names of the modules declared test-only
/// (`#[cfg(test)] mod tests;`), whose files are test code.
fn drop_test_code(toks: &[Token]) -> (Vec<Token>, Vec<String>) {
    let mut kept = Vec::new();
    let mut test_modules = Vec::new();
    let mut i = 0;
    while i < toks.len() {
        if let Some(mut j) = test_attribute_end(toks, i) {
            while let Some(next) = attribute_end(toks, j) {
                j = next;
            }
            let (end, module) = item_end(toks, j);
            test_modules.extend(module);
            i = end;
        } else {
            kept.push(toks[i].clone());
            i += 1;
        }
    }
    (kept, test_modules)
}

// ---------------------------------------------------------------------------------------------
// Paths: `use` trees and paths in code, resolved to files.

/// A path as written, split at `::`, with its line (a `use` leaf's: the line of its last segment).
struct Written {
    segments: Vec<String>,
    line: usize,
    /// The name a `use` leaf brings into scope (its last segment or its `as` name).
    name: Option<String>,
    /// Written in code, not in a `use`: the last segment is an item, never a module.
    in_code: bool,
}

/// The leaves of the `use` tree starting at `*i` (just after `use`), appended to `out`; `*i`
/// ends past the tree.
fn use_tree(toks: &[Token], i: &mut usize, prefix: &[String], out: &mut Vec<Written>) {
    let mut path = prefix.to_vec();
    while let Some(t) = toks.get(*i) {
        match &t.tok {
            Tok::Ident(s) => {
                path.push(s.clone());
                *i += 1;
                if toks.get(*i).is_some_and(|t| t.tok == Tok::Sep) {
                    *i += 1;
                    continue;
                }
                let mut name = Some(s.clone());
                if toks.get(*i).and_then(Token::ident) == Some("as") {
                    name = toks.get(*i + 1).and_then(Token::ident).map(str::to_owned);
                    *i += 2;
                }
                if s == "self" {
                    path.pop();
                    name = name
                        .filter(|n| n != "self")
                        .or_else(|| path.last().cloned());
                }
                out.push(Written {
                    segments: path,
                    line: t.line,
                    name,
                    in_code: false,
                });
                return;
            }
            Tok::Punct('{') => {
                *i += 1;
                while let Some(t) = toks.get(*i) {
                    if t.is('}') {
                        *i += 1;
                        break;
                    }
                    if t.is(',') {
                        *i += 1;
                        continue;
                    }
                    let before = *i;
                    use_tree(toks, i, &path, out);
                    if *i == before {
                        *i += 1;
                    }
                }
                return;
            }
            Tok::Punct('*') => {
                *i += 1;
                out.push(Written {
                    segments: path,
                    line: t.line,
                    name: None,
                    in_code: false,
                });
                return;
            }
            // A leading `::` (an external crate): nothing of ours.
            _ => return,
        }
    }
}

/// One import: a file, the line, the path as resolved (`crate::fit::Param`) and the file that
/// defines the module it reaches.
#[derive(Clone, Debug)]
struct Import {
    from: String,
    line: usize,
    path: String,
    to: String,
}

/// The module path of a file: `fit/select/forward.rs` is `fit::select::forward`,
/// `fit/select/mod.rs` is `fit::select`, `lib.rs` and `main.rs` are the crate roots.
fn module_path(file: &str) -> Vec<String> {
    let stem = file.strip_suffix(".rs").unwrap_or(file);
    let mut segments: Vec<String> = stem.split('/').map(str::to_owned).collect();
    if matches!(
        segments.last().map(String::as_str),
        Some("mod" | "lib" | "main")
    ) {
        segments.pop();
    }
    segments
}

/// The folder holding a file's child modules: `fit/` for `fit/mod.rs`, `bench/` for
/// `bench.rs`, nothing for the crate roots.
fn child_dir(file: &str) -> String {
    module_path(file).iter().map(|s| format!("{s}/")).collect()
}

/// The folder a module file sits in as a name: `fit/select/` for `fit/select/forward.rs`,
/// `fit/` for `fit/select/mod.rs`.
fn home_dir(file: &str) -> String {
    let path = module_path(file);
    let parent = &path[..path.len().saturating_sub(1)];
    parent.iter().map(|s| format!("{s}/")).collect()
}

/// Whether a file belongs to the binary (`main.rs`, `cli/`), whose `crate` is not the library.
fn in_binary(file: &str) -> bool {
    file == "main.rs" || file.starts_with("cli/")
}

/// The files that are modules (test code left out), and those declared private (`mod x;`, not
/// `pub mod x;`).
struct Modules {
    files: BTreeSet<String>,
    private: BTreeSet<String>,
}

impl Modules {
    /// The file defining the module `name` in the folder `dir`, if there is one.
    fn file(&self, dir: &str, name: &str) -> Option<String> {
        [format!("{dir}{name}.rs"), format!("{dir}{name}/mod.rs")]
            .into_iter()
            .find(|f| self.files.contains(f))
    }

    /// Whether `from` may name the module defined in `file`: a private one only from the module
    /// declaring it and below.
    fn visible(&self, file: &str, from: &str) -> bool {
        let home = home_dir(file);
        !self.private.contains(file) || from.starts_with(&home) || child_dir(from) == home
    }

    /// The file of the deepest module along an absolute path written in `from` (the crate root
    /// if none), and how many segments were modules. The last segment of a path in code is an
    /// item (`item_last`); the last of a `use` is a module only where `from` may see it, else it
    /// is the item of that name (`select::forward`, the function `select/mod.rs` re-exports from
    /// its private `forward.rs`).
    fn resolve(&self, from: &str, path: &[String], item_last: bool) -> (String, usize) {
        let mut target = if in_binary(from) { "main.rs" } else { "lib.rs" }.to_owned();
        let mut dir = String::new();
        let mut depth = 0;
        let names = &path[..path.len() - usize::from(item_last && !path.is_empty())];
        for (k, segment) in names.iter().enumerate() {
            let Some(file) = self.file(&dir, segment) else {
                break;
            };
            if k + 1 == path.len() && !self.visible(&file, from) {
                break;
            }
            target = file;
            dir = format!("{dir}{segment}/");
            depth += 1;
        }
        (target, depth)
    }
}

/// What a file's paths may start with besides `crate`, `super` and `self`.
struct Scope {
    /// Child modules the file declares (`mod forward;`), by name.
    children: BTreeSet<String>,
    /// Modules a `use` brought in, by the name in scope, with their absolute module path.
    modules: BTreeMap<String, Vec<String>>,
}

/// The absolute path (from the crate root) of a path written in `file`, if it is one of ours.
fn absolute(file: &str, written: &[String], scope: &Scope) -> Option<Vec<String>> {
    let here = module_path(file);
    let first = written.first()?.as_str();
    let (mut path, rest) = match first {
        "crate" => (Vec::new(), &written[1..]),
        "appell" if in_binary(file) => (Vec::new(), &written[1..]),
        "self" => (here, &written[1..]),
        "super" => {
            let up = written.iter().take_while(|s| *s == "super").count();
            let keep = here.len().checked_sub(up)?;
            (here[..keep].to_vec(), &written[up..])
        }
        name if scope.children.contains(name) => (here, written),
        name => (scope.modules.get(name)?.clone(), &written[1..]),
    };
    path.extend(rest.iter().filter(|s| *s != "self").cloned());
    Some(path)
}

/// The `mod name;` declarations among tokens: the name and whether it is `pub` (in any form).
fn declarations(toks: &[Token]) -> Vec<(String, bool)> {
    let mut out = Vec::new();
    for (k, w) in toks.windows(3).enumerate() {
        if let (Some("mod"), Some(name), true) = (w[0].ident(), w[1].ident(), w[2].is(';')) {
            let public = k > 0 && (toks[k - 1].ident() == Some("pub") || toks[k - 1].is(')'));
            out.push((name.to_owned(), public));
        }
    }
    out
}

/// The imports of one file (already free of test code).
fn imports_of(modules: &Modules, file: &str, toks: &[Token]) -> Vec<Import> {
    let dir = child_dir(file);
    let mut scope = Scope {
        children: declarations(toks)
            .into_iter()
            .map(|(name, _)| name)
            .filter(|name| modules.file(&dir, name).is_some())
            .collect(),
        modules: BTreeMap::new(),
    };
    // The `use` trees first: they name the modules later paths may start with.
    let mut written = Vec::new();
    let mut in_use = vec![false; toks.len()];
    let mut i = 0;
    while i < toks.len() {
        if toks[i].ident() == Some("use") {
            let start = i;
            i += 1;
            let mut leaves = Vec::new();
            use_tree(toks, &mut i, &[], &mut leaves);
            while i < toks.len() && !toks[i].is(';') {
                i += 1;
            }
            in_use[start..(i + 1).min(toks.len())].fill(true);
            written.extend(leaves);
        } else {
            i += 1;
        }
    }
    for w in &written {
        let (Some(name), Some(path)) = (&w.name, absolute(file, &w.segments, &scope)) else {
            continue;
        };
        if !path.is_empty() && modules.resolve(file, &path, false).1 == path.len() {
            scope.modules.insert(name.clone(), path);
        }
    }
    // Paths in code: a start we know, not itself after `::`, followed by `::`.
    let mut i = 0;
    while i < toks.len() {
        let starts = !in_use[i]
            && toks.get(i + 1).is_some_and(|t| t.tok == Tok::Sep)
            && (i == 0 || toks[i - 1].tok != Tok::Sep)
            && toks[i].ident().is_some_and(|s| {
                matches!(s, "crate" | "super" | "self")
                    || (s == "appell" && in_binary(file))
                    || scope.children.contains(s)
                    || scope.modules.contains_key(s)
            });
        if !starts {
            i += 1;
            continue;
        }
        let mut segments = vec![toks[i].ident().unwrap().to_owned()];
        let line = toks[i].line;
        i += 1;
        while toks.get(i).is_some_and(|t| t.tok == Tok::Sep) {
            match toks.get(i + 1).and_then(Token::ident) {
                Some(s) => segments.push(s.to_owned()),
                None => break,
            }
            i += 2;
        }
        written.push(Written {
            segments,
            line,
            name: None,
            in_code: true,
        });
    }
    let mut out = Vec::new();
    for w in written {
        let Some(path) = absolute(file, &w.segments, &scope) else {
            continue;
        };
        let (to, _) = modules.resolve(file, &path, w.in_code);
        if to == file || to == "lib.rs" {
            continue;
        }
        let shown = std::iter::once("crate".to_owned())
            .chain(path)
            .collect::<Vec<_>>()
            .join("::");
        out.push(Import {
            from: file.to_owned(),
            line: w.line,
            path: shown,
            to,
        });
    }
    out.sort_by(|a, b| (a.line, &a.to, &a.path).cmp(&(b.line, &b.to, &b.path)));
    out
}

/// Every import of `src/` outside test code, and the files that are test code.
fn all_imports(files: &Files) -> (Vec<Import>, BTreeSet<String>) {
    let mut clean = BTreeMap::new();
    let mut test_files = BTreeSet::new();
    for (file, text) in files {
        let (kept, test_modules) = drop_test_code(&tokenize(text));
        let dir = child_dir(file);
        for m in test_modules {
            test_files.insert(format!("{dir}{m}.rs"));
            test_files.insert(format!("{dir}{m}/"));
        }
        clean.insert(file.clone(), kept);
    }
    let is_test = |f: &str| {
        test_files
            .iter()
            .any(|t| f == t || (t.ends_with('/') && f.starts_with(t.as_str())))
    };
    let mut modules = Modules {
        files: files.keys().filter(|f| !is_test(f)).cloned().collect(),
        private: BTreeSet::new(),
    };
    for (file, toks) in &clean {
        let dir = child_dir(file);
        for (name, public) in declarations(toks) {
            if let Some(child) = modules.file(&dir, &name).filter(|_| !public) {
                modules.private.insert(child);
            }
        }
    }
    let mut imports = Vec::new();
    for (file, toks) in &clean {
        if modules.files.contains(file) {
            imports.extend(imports_of(&modules, file, toks));
        }
    }
    let test_files = files.keys().filter(|f| is_test(f)).cloned().collect();
    (imports, test_files)
}

// ---------------------------------------------------------------------------------------------
// The rules.

/// A file's top-level module (`cli` for the binary), `None` for `lib.rs`.
fn top_module(file: &str) -> Option<&str> {
    match file {
        "lib.rs" => None,
        "main.rs" => Some("cli"),
        _ => {
            let first = file.split('/').next().unwrap_or(file);
            Some(first.strip_suffix(".rs").unwrap_or(first))
        }
    }
}

fn layer_of(module: &str) -> Option<usize> {
    LAYERS.iter().position(|layer| layer.contains(&module))
}

fn layer_name(layer: usize) -> String {
    LAYERS[layer].join(", ")
}

/// Whether `to` is the face (`mod.rs`, or `bench.rs` beside `bench/`) of a folder holding
/// `from`: an import back up from a file to the face that declares it or one of its folders.
fn imports_enclosing_face(from: &str, to: &str) -> bool {
    let dir = child_dir(to);
    !dir.is_empty() && from != to && from.starts_with(&dir)
}

/// The deepest folder holding all the files (`fit/`, `sim/` for `sim/mod.rs` and
/// `sim/hybrid/*.rs`, nothing for `src/` itself).
fn common_folder(files: &[String]) -> String {
    let dirs: Vec<Vec<&str>> = files
        .iter()
        .map(|f| {
            let mut parts: Vec<&str> = f.split('/').collect();
            parts.pop();
            parts
        })
        .collect();
    let mut common: Vec<&str> = dirs.first().cloned().unwrap_or_default();
    for d in &dirs {
        let same = common.iter().zip(d).take_while(|(a, b)| a == b).count();
        common.truncate(same);
    }
    common.iter().map(|s| format!("{s}/")).collect()
}

/// One loop: its folder, its files (one strongly connected component of a layer's file graph),
/// the imports among them and what is left of it without the imports up to a face.
#[derive(Debug)]
struct Loop {
    folder: String,
    files: Vec<String>,
    imports: Vec<Import>,
    /// The loops left among the files once no file imports the face of a folder holding it.
    without_faces: Vec<Vec<String>>,
}

impl Loop {
    fn new(files: Vec<String>, imports: Vec<Import>) -> Loop {
        let rest: Vec<&Import> = imports
            .iter()
            .filter(|i| !imports_enclosing_face(&i.from, &i.to))
            .collect();
        Loop {
            folder: common_folder(&files),
            without_faces: strongly_connected(&rest),
            files,
            imports,
        }
    }

    /// The (file, face) pairs where a file of the loop imports the face of a folder holding it.
    fn up_to_faces(&self) -> BTreeSet<(&str, &str)> {
        self.imports
            .iter()
            .filter(|i| imports_enclosing_face(&i.from, &i.to))
            .map(|i| (i.from.as_str(), i.to.as_str()))
            .collect()
    }

    /// One line: where, how big, how much of it is the faces'.
    fn header(&self) -> String {
        let left: Vec<String> = self
            .without_faces
            .iter()
            .map(|c| format!("{} files in {}", c.len(), common_folder(c)))
            .collect();
        format!(
            "loop in {}: {} files import each other ({} imports among them; {} times a file \
             imports back up the face (mod.rs) of a folder holding it, counted once per file \
             and face, marked ^; without those imports: {})",
            if self.folder.is_empty() {
                "src/"
            } else {
                &self.folder
            },
            self.files.len(),
            self.imports.len(),
            self.up_to_faces().len(),
            if left.is_empty() {
                "no loop".to_owned()
            } else {
                format!("a loop of {}", left.join(", a loop of "))
            }
        )
    }
}

impl fmt::Display for Loop {
    /// The header, then each file with its imports inside the loop, one line per line of code
    /// and file imported (`{:#}`: the files only).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "{}", self.header())?;
        for file in &self.files {
            writeln!(f, "    {file}")?;
            if f.alternate() {
                continue;
            }
            let mine: Vec<&Import> = self.imports.iter().filter(|i| &i.from == file).collect();
            for group in mine.chunk_by(|a, b| a.line == b.line && a.to == b.to) {
                let mark = if imports_enclosing_face(&group[0].from, &group[0].to) {
                    '^'
                } else {
                    ' '
                };
                let paths: Vec<&str> = group.iter().map(|i| i.path.as_str()).collect();
                writeln!(
                    f,
                    "      {mark} :{} {} -> {}",
                    group[0].line,
                    joined(&paths),
                    group[0].to
                )?;
            }
        }
        Ok(())
    }
}

/// Paths of one line in one brace: `crate::fit::{Param, Estimate}`.
fn joined(paths: &[&str]) -> String {
    let mut prefix: Vec<&str> = paths[0].split("::").collect();
    for p in paths {
        let segments: Vec<&str> = p.split("::").collect();
        let same = prefix
            .iter()
            .zip(&segments)
            .take_while(|(a, b)| a == b)
            .count();
        prefix.truncate(same.min(segments.len() - 1));
    }
    let mut rests: Vec<String> = paths
        .iter()
        .map(|p| {
            let segments: Vec<&str> = p.split("::").collect();
            segments[prefix.len()..].join("::")
        })
        .collect();
    rests.dedup();
    if rests.len() == 1 {
        paths[0].to_owned()
    } else {
        format!("{}::{{{}}}", prefix.join("::"), rests.join(", "))
    }
}

/// What the check found.
#[derive(Debug, Default)]
struct Report {
    /// Files read as modules (test code and `lib.rs` left out).
    files: usize,
    /// Imports found (each leaf of a `use` tree and each path in code).
    imports: usize,
    /// Imports running up the layers without an exception.
    upward: Vec<String>,
    /// Imports running up the layers under an exception, with its reason.
    excused: Vec<String>,
    /// Exceptions matching nothing.
    stale: Vec<String>,
    /// Top-level modules not placed in [`LAYERS`].
    unplaced: BTreeSet<String>,
    /// Loops inside a layer without an exception.
    loops: Vec<Loop>,
    /// Loops under an exception, with its reason.
    excused_loops: Vec<(Loop, &'static str)>,
    /// Files left out as test code.
    test_files: BTreeSet<String>,
}

impl Report {
    fn is_clean(&self) -> bool {
        self.upward.is_empty()
            && self.stale.is_empty()
            && self.unplaced.is_empty()
            && self.loops.is_empty()
    }
}

impl fmt::Display for Report {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "src/: {} files, {} imports (test code left out, with the files {:?})",
            self.files, self.imports, self.test_files
        )?;
        let layers: Vec<String> = (0..LAYERS.len()).map(layer_name).collect();
        writeln!(f, "layers, bottom first: {}", layers.join(" < "))?;
        if !self.unplaced.is_empty() {
            writeln!(f, "\nTop-level modules missing from LAYERS:")?;
            for m in &self.unplaced {
                writeln!(f, "  {m}")?;
            }
        }
        writeln!(f, "\nImports up the layers: {}", self.upward.len())?;
        for line in &self.upward {
            writeln!(f, "  {line}")?;
        }
        writeln!(f, "\nLoops inside a layer: {}", self.loops.len())?;
        for (n, l) in self.loops.iter().enumerate() {
            write!(f, "  {}. {l}", n + 1)?;
        }
        if !self.stale.is_empty() {
            writeln!(
                f,
                "\nExceptions that no longer fit (delete or update them):"
            )?;
            for line in &self.stale {
                writeln!(f, "  {line}")?;
            }
        }
        writeln!(
            f,
            "\nAllowed for now by UPWARD_EXCEPTIONS: {}",
            self.excused.len()
        )?;
        for line in &self.excused {
            writeln!(f, "  {line}")?;
        }
        writeln!(
            f,
            "\nAllowed for now by LOOP_EXCEPTIONS: {}",
            self.excused_loops.len()
        )?;
        for (l, reason) in &self.excused_loops {
            write!(f, "  {l:#}")?;
            writeln!(f, "    because: {reason}")?;
        }
        Ok(())
    }
}

/// Checks both rules on a tree of sources.
fn check(files: &Files, upward: &[Exception], loops: &[LoopException]) -> Report {
    let (imports, test_files) = all_imports(files);
    let mut report = Report {
        files: files.len() - test_files.len() - usize::from(files.contains_key("lib.rs")),
        imports: imports.len(),
        test_files,
        ..Report::default()
    };
    let mut used = vec![false; upward.len()];
    for i in &imports {
        let (Some(from), Some(to)) = (top_module(&i.from), top_module(&i.to)) else {
            continue;
        };
        let (Some(low), Some(high)) = (layer_of(from), layer_of(to)) else {
            let missing = [from, to].into_iter().filter(|m| layer_of(m).is_none());
            report.unplaced.extend(missing.map(str::to_owned));
            continue;
        };
        if high <= low {
            continue;
        }
        let line = format!(
            "{}:{} imports {} (layer {} above {})",
            i.from,
            i.line,
            i.path,
            layer_name(high),
            layer_name(low)
        );
        let excuse = upward.iter().position(|e| {
            e.file == i.from && (i.path == e.path || i.path.starts_with(&format!("{}::", e.path)))
        });
        match excuse {
            Some(k) => {
                used[k] = true;
                report.excused.push(format!("{line}: {}", upward[k].reason));
            }
            None => report.upward.push(line),
        }
    }
    for (e, used) in upward.iter().zip(used) {
        if !used {
            report.stale.push(format!("{} imports {}", e.file, e.path));
        }
    }
    let mut used = vec![false; loops.len()];
    for layer in 0..LAYERS.len() {
        let in_layer = |f: &str| top_module(f).and_then(layer_of) == Some(layer);
        let inside: Vec<&Import> = imports
            .iter()
            .filter(|i| in_layer(&i.from) && in_layer(&i.to))
            .collect();
        for component in strongly_connected(&inside) {
            let among: Vec<Import> = inside
                .iter()
                .filter(|i| component.contains(&i.from) && component.contains(&i.to))
                .map(|&i| i.clone())
                .collect();
            let found = Loop::new(component, among);
            let excuse = loops.iter().position(|e| e.folder == found.folder);
            match excuse {
                Some(k) if found.files.len() <= loops[k].files => {
                    used[k] = true;
                    report.excused_loops.push((found, loops[k].reason));
                }
                Some(k) => {
                    used[k] = true;
                    report.stale.push(format!(
                        "the loop in {} has grown past the {} files allowed",
                        loops[k].folder, loops[k].files
                    ));
                    report.loops.push(found);
                }
                None => report.loops.push(found),
            }
        }
    }
    for (e, used) in loops.iter().zip(used) {
        if !used {
            report
                .stale
                .push(format!("no loop in {} any more", e.folder));
        }
    }
    report
}

/// The strongly connected components of more than one file (Tarjan), each sorted.
fn strongly_connected(imports: &[&Import]) -> Vec<Vec<String>> {
    let mut edges: BTreeMap<&str, BTreeSet<&str>> = BTreeMap::new();
    for i in imports {
        edges
            .entry(i.from.as_str())
            .or_default()
            .insert(i.to.as_str());
        edges.entry(i.to.as_str()).or_default();
    }
    struct Tarjan<'a> {
        edges: &'a BTreeMap<&'a str, BTreeSet<&'a str>>,
        index: BTreeMap<&'a str, usize>,
        low: BTreeMap<&'a str, usize>,
        stack: Vec<&'a str>,
        on_stack: BTreeSet<&'a str>,
        out: Vec<Vec<String>>,
    }
    impl<'a> Tarjan<'a> {
        fn visit(&mut self, v: &'a str) {
            let n = self.index.len();
            self.index.insert(v, n);
            self.low.insert(v, n);
            self.stack.push(v);
            self.on_stack.insert(v);
            let edges = self.edges;
            for &w in &edges[v] {
                if !self.index.contains_key(w) {
                    self.visit(w);
                    let low = self.low[v].min(self.low[w]);
                    self.low.insert(v, low);
                } else if self.on_stack.contains(w) {
                    let low = self.low[v].min(self.index[w]);
                    self.low.insert(v, low);
                }
            }
            if self.low[v] == self.index[v] {
                let mut component = Vec::new();
                while let Some(w) = self.stack.pop() {
                    self.on_stack.remove(w);
                    component.push(w.to_owned());
                    if w == v {
                        break;
                    }
                }
                if component.len() > 1 {
                    component.sort();
                    self.out.push(component);
                }
            }
        }
    }
    let mut tarjan = Tarjan {
        edges: &edges,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on_stack: BTreeSet::new(),
        out: Vec::new(),
    };
    for &v in edges.keys() {
        if !tarjan.index.contains_key(v) {
            tarjan.visit(v);
        }
    }
    tarjan.out.sort();
    tarjan.out
}

// ---------------------------------------------------------------------------------------------
// The tests.

#[test]
fn src_keeps_its_layers_and_has_no_loops() {
    let report = check(&read_src(), &UPWARD_EXCEPTIONS, &LOOP_EXCEPTIONS);
    assert!(
        report.is_clean(),
        "the architecture of src/ is broken:\n{report}"
    );
}

/// The parser reads the real tree into a graph of the size it has, so the rules cannot pass for
/// finding nothing.
#[test]
fn src_reads_into_a_full_graph() {
    let files = read_src();
    let (imports, test_files) = all_imports(&files);
    let report = check(&files, &UPWARD_EXCEPTIONS, &LOOP_EXCEPTIONS);
    assert!(report.files > 100, "{} files", report.files);
    assert!(imports.len() > 300, "{} imports", imports.len());
    let edges: BTreeSet<(&str, &str)> = imports
        .iter()
        .map(|i| (i.from.as_str(), i.to.as_str()))
        .collect();
    for edge in [
        ("scene.rs", "sim/mod.rs"),
        ("scene.rs", "model/mod.rs"),
        ("sim/hybrid/mod.rs", "sim/rk.rs"),
        ("sim/hybrid/mod.rs", "sim/hybrid/decide.rs"),
        ("data/synth.rs", "scene.rs"),
        ("main.rs", "cpu.rs"),
        ("main.rs", "cli/mod.rs"),
    ] {
        assert!(edges.contains(&edge), "{edge:?} missing");
    }
    assert!(test_files.contains("sim/hybrid/tests.rs"), "{test_files:?}");
    assert!(
        imports.iter().all(|i| i.from != "sim/hybrid/tests.rs"),
        "a test module's file is test code"
    );
}

fn tree(files: &[(&str, &str)]) -> Files {
    files
        .iter()
        .map(|&(f, text)| (f.to_owned(), text.to_owned()))
        .collect()
}

fn import_list(files: &Files) -> Vec<(String, usize, String, String)> {
    all_imports(files)
        .0
        .into_iter()
        .map(|i| (i.from, i.line, i.path, i.to))
        .collect()
}

#[test]
fn checker_catches_an_import_up_the_layers() {
    let files = tree(&[
        ("lib.rs", "pub mod model;\npub mod sim;\n"),
        (
            "model/mod.rs",
            "//! Model.\n\nuse crate::sim::Options;\nfn f() {\n    crate::sim::run();\n}\n",
        ),
        (
            "sim/mod.rs",
            "use crate::model::Rig;\npub struct Options;\n",
        ),
    ]);
    let report = check(&files, &[], &[]);
    assert_eq!(
        report.upward,
        [
            "model/mod.rs:3 imports crate::sim::Options (layer sim above model)",
            "model/mod.rs:5 imports crate::sim::run (layer sim above model)",
        ],
        "{report}"
    );
    assert!(report.loops.is_empty() && !report.is_clean(), "{report}");
    // An exception lets it pass, with its reason in the report.
    let excused = [Exception {
        file: "model/mod.rs",
        path: "crate::sim",
        reason: "because",
    }];
    let report = check(&files, &excused, &[]);
    assert!(report.is_clean(), "{report}");
    assert_eq!(report.excused.len(), 2, "{report}");
    // An exception matching nothing fails.
    let stale = [Exception {
        file: "sim/mod.rs",
        path: "crate::model::Rig",
        reason: "not upward",
    }];
    let report = check(&files, &stale, &[]);
    assert_eq!(report.stale, ["sim/mod.rs imports crate::model::Rig"]);
    assert!(!report.is_clean());
}

#[test]
fn checker_catches_a_two_file_loop() {
    let files = tree(&[
        ("fit/mod.rs", "mod a;\nmod b;\npub use a::X;\n"),
        ("fit/a.rs", "pub struct X;\nfn f() { super::b::g(); }\n"),
        ("fit/b.rs", "use crate::fit::a::X;\npub fn g() {}\n"),
    ]);
    let report = check(&files, &[], &[]);
    assert_eq!(report.loops.len(), 1, "{report}");
    assert_eq!(report.loops[0].files, ["fit/a.rs", "fit/b.rs"], "{report}");
    assert!(report.upward.is_empty() && !report.is_clean());
    // An exception by folder lets it pass while it holds no more files than allowed.
    let allow = |files| {
        [LoopException {
            folder: "fit/",
            files,
            reason: "because",
        }]
    };
    let report = check(&files, &[], &allow(2));
    assert!(
        report.is_clean() && report.excused_loops.len() == 1,
        "{report}"
    );
    let report = check(&files, &[], &allow(1));
    assert!(!report.is_clean() && report.loops.len() == 1, "{report}");
    let clean = tree(&[("fit/mod.rs", "mod a;\npub use a::X;\n"), ("fit/a.rs", "")]);
    let report = check(&clean, &[], &allow(2));
    assert_eq!(report.stale, ["no loop in fit/ any more"], "{report}");
    // A child taking an item from the face that re-exports from it is a loop as well.
    let files = tree(&[
        (
            "fit/mod.rs",
            "mod lm;\npub use lm::solve;\npub enum Param {}\n",
        ),
        ("fit/lm.rs", "use super::Param;\npub fn solve() {}\n"),
    ]);
    let report = check(&files, &[], &[]);
    assert_eq!(report.loops.len(), 1, "{report}");
    assert_eq!(
        report.loops[0].files,
        ["fit/lm.rs", "fit/mod.rs"],
        "{report}"
    );
    assert!(
        report
            .to_string()
            .contains("^ :1 crate::fit::Param -> fit/mod.rs"),
        "{report}"
    );
}

#[test]
fn checker_accepts_a_clean_tree() {
    let files = tree(&[
        ("lib.rs", "pub mod fit;\npub mod model;\npub mod report;\n"),
        ("model/mod.rs", "pub mod rig;\npub use rig::Rig;\n"),
        ("model/rig.rs", "/// Not `crate::fit::Fit`.\npub struct Rig;\n"),
        (
            "fit/mod.rs",
            "mod select;\nmod words;\npub use select::run;\npub use words::Param;\n\
             #[cfg(test)]\nmod tests {\n    use crate::report::Table;\n    fn f() { let c = '}'; }\n}\n",
        ),
        ("fit/words.rs", "pub enum Param {}\n"),
        (
            "fit/select/mod.rs",
            "mod forward;\npub use forward::run;\n",
        ),
        (
            "fit/select/forward.rs",
            "use crate::fit::words::Param;\nuse crate::model::{self, rig::{Rig}};\n\
             pub fn run() -> &'static str {\n    let _ = model::Rig;\n    \
             \"crate::report::Table\" // crate::report\n}\n/* crate::fit::select */\n",
        ),
        ("report/mod.rs", "use crate::fit::{run, Param};\npub struct Table;\n"),
    ]);
    let report = check(&files, &[], &[]);
    assert!(report.is_clean(), "{report}");
    assert_eq!(report.files, 7);
    assert_eq!(
        import_list(&files)
            .into_iter()
            .filter(|e| e.0 == "fit/select/forward.rs")
            .collect::<Vec<_>>(),
        [
            (
                "fit/select/forward.rs".to_owned(),
                1,
                "crate::fit::words::Param".to_owned(),
                "fit/words.rs".to_owned()
            ),
            (
                "fit/select/forward.rs".to_owned(),
                2,
                "crate::model".to_owned(),
                "model/mod.rs".to_owned()
            ),
            (
                "fit/select/forward.rs".to_owned(),
                2,
                "crate::model::rig::Rig".to_owned(),
                "model/rig.rs".to_owned()
            ),
            (
                "fit/select/forward.rs".to_owned(),
                4,
                "crate::model::Rig".to_owned(),
                "model/mod.rs".to_owned()
            ),
        ]
    );
}

#[test]
fn paths_resolve_to_the_files_defining_their_modules() {
    let files = tree(&[
        ("main.rs", "mod cli;\nfn main() { appell::cpu::check(); cli::run(); }\n"),
        ("cli/mod.rs", "mod fit;\npub fn run() { fit::go(); }\n"),
        ("cli/fit.rs", "use appell::fit::{self as f, select::forward};\npub fn go() {}\n"),
        ("cpu.rs", "pub fn check() {}\n"),
        ("fit/mod.rs", "pub mod select;\npub struct FitReport;\n"),
        ("fit/select/mod.rs", "mod forward;\nmod score;\n"),
        (
            "fit/select/forward.rs",
            "use super::super::FitReport;\nuse self::inner::X;\n\
             pub fn a() -> r#\"crate::plan\"# { super::score::s(); crate::fit::select::score::s() }\n\
             macro_rules! m { () => { use $crate::fit::FitReport; } }\n",
        ),
        (
            "fit/select/score.rs",
            "use super::*;\nuse super::forward::a;\npub(crate) fn s() {}\n",
        ),
    ]);
    let found: Vec<(String, usize, String)> = import_list(&files)
        .into_iter()
        .map(|(from, line, _, to)| (from, line, to))
        .collect();
    let want = [
        ("cli/fit.rs", 1, "fit/mod.rs"),
        // `forward.rs` is private to select/: from outside, `select::forward` is an item of the
        // face (as the function `select::forward` the face re-exports).
        ("cli/fit.rs", 1, "fit/select/mod.rs"),
        ("cli/mod.rs", 2, "cli/fit.rs"),
        ("fit/select/forward.rs", 1, "fit/mod.rs"),
        ("fit/select/forward.rs", 3, "fit/select/score.rs"),
        ("fit/select/forward.rs", 3, "fit/select/score.rs"),
        ("fit/select/forward.rs", 4, "fit/mod.rs"),
        ("fit/select/score.rs", 1, "fit/select/mod.rs"),
        ("fit/select/score.rs", 2, "fit/select/forward.rs"),
        ("main.rs", 2, "cli/mod.rs"),
        ("main.rs", 2, "cpu.rs"),
    ];
    let want: Vec<(String, usize, String)> = want
        .iter()
        .map(|&(f, l, t)| (f.to_owned(), l, t.to_owned()))
        .collect();
    let mut found = found;
    found.sort();
    assert_eq!(found, want);
}

#[test]
fn test_code_is_left_out() {
    let text = "pub struct S {\n    #[cfg(test)]\n    hook: fn() -> bool,\n    kept: u8,\n}\n\
                #[cfg(all(test, unix))]\nimpl<A, B> S { fn f() {} }\n\
                #[cfg(not(test))]\nfn g() {}\n#[cfg(test)]\nmod tests;\n";
    let (kept, test_modules) = drop_test_code(&tokenize(text));
    let words: Vec<&str> = kept.iter().filter_map(Token::ident).collect();
    assert_eq!(
        words,
        ["pub", "struct", "S", "kept", "u8", "cfg", "not", "test", "fn", "g"]
    );
    assert_eq!(test_modules, ["tests"]);
}
