//! Every output the docs show is what the command gives today. In README.md, docs/*.md and
//! tests/data/README.md an
//! output block (```text) is preceded by a comment naming the command that made it,
//! `<!-- output of: appell ... -->`, or says why it is not checked, `<!-- not checked: ... -->`
//! (prose, a file's contents, an output that depends on the machine). The command runs with
//! `appell` standing for the binary under test, in a scratch directory that links the
//! repository's `configs/`, `data/`, `docs/` and `tests/`, so what it writes stays there.
//!
//! How a block matches: a line `...` skips any number of lines; a line ending in ` ...`
//! matches any line that starts with the text before it; every other line must be an output
//! line exactly (trailing spaces aside). The pieces between `...` lines are consecutive lines of
//! the output and come in order; stderr is searched before stdout (notes come first) and then
//! the other way round.

use super::doc_links::{documents, root};
use std::path::Path;
use std::process::Command;

/// What a document's comment says of the output block after it.
#[derive(Debug, Clone, PartialEq)]
enum Marker {
    /// The command that makes the block.
    Output(String),
    /// Why the block is not an output to compare.
    NotChecked,
}

/// One output block with its marker and where it is.
#[derive(Debug)]
struct Block {
    doc: String,
    line: usize,
    marker: Option<Marker>,
    text: Vec<String>,
}

/// The marker a line holds, if any.
fn marker(line: &str) -> Option<Marker> {
    let inner = line
        .trim()
        .strip_prefix("<!--")?
        .strip_suffix("-->")?
        .trim();
    if let Some(cmd) = inner.strip_prefix("output of:") {
        return Some(Marker::Output(cmd.trim().to_owned()));
    }
    inner
        .strip_prefix("not checked:")
        .map(|_| Marker::NotChecked)
}

/// Every ```text block of `text` with the marker on the last non-blank line before it (which
/// may be the line just before another block's fence: the marker goes right above its block).
fn blocks(doc: &str, text: &str) -> Vec<Block> {
    let lines: Vec<&str> = text.lines().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < lines.len() {
        let fence = lines[i].trim_start();
        if !fence.starts_with("```") {
            i += 1;
            continue;
        }
        let lang = fence.trim_start_matches('`').trim();
        let start = i;
        i += 1;
        let mut body = Vec::new();
        while i < lines.len() && !lines[i].trim_start().starts_with("```") {
            body.push(lines[i].trim_end().to_owned());
            i += 1;
        }
        i += 1;
        if lang == "text" {
            let marker = lines[..start]
                .iter()
                .rev()
                .find(|l| !l.trim().is_empty())
                .and_then(|l| marker(l));
            out.push(Block {
                doc: doc.to_owned(),
                line: start + 1,
                marker,
                text: body,
            });
        }
    }
    out
}

/// The expected lines cut at `...` lines.
fn pieces(expected: &[String]) -> Vec<Vec<String>> {
    let mut out = vec![Vec::new()];
    for l in expected {
        if l.trim() == "..." {
            out.push(Vec::new());
        } else {
            out.last_mut().unwrap().push(l.clone());
        }
    }
    out.retain(|p| !p.is_empty());
    out
}

/// Whether output line `got` is what expected line `want` shows.
fn line_matches(want: &str, got: &str) -> bool {
    let got = got.trim_end();
    match want.strip_suffix(" ...") {
        Some(prefix) => got.starts_with(prefix.trim_end()),
        None => want.trim_end() == got,
    }
}

/// Whether every piece occurs in `output` as consecutive lines, the pieces in order. On
/// failure, the first piece not found.
fn matches(expected: &[String], output: &str) -> Result<(), Vec<String>> {
    let lines: Vec<&str> = output.lines().collect();
    let mut at = 0;
    for piece in pieces(expected) {
        let found = (at..lines.len()).find(|&s| {
            s + piece.len() <= lines.len()
                && piece
                    .iter()
                    .zip(&lines[s..])
                    .all(|(w, g)| line_matches(w, g))
        });
        match found {
            Some(s) => at = s + piece.len(),
            None => return Err(piece),
        }
    }
    Ok(())
}

/// A scratch directory linking the repository's folders, to run documented commands in.
fn scratch() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    for d in ["configs", "data", "docs", "tests", "scripts"] {
        std::os::unix::fs::symlink(root().join(d), dir.path().join(d)).unwrap();
    }
    dir
}

/// Run a documented command line (`appell ARGS`, shell words without quotes or pipes) in
/// `dir`: its stdout and stderr.
fn run(command: &str, dir: &Path) -> (String, String) {
    let words: Vec<&str> = command.split_whitespace().collect();
    assert_eq!(
        words.first(),
        Some(&"appell"),
        "a documented command starts with appell: {command}"
    );
    assert!(
        !command.contains(['|', '>', '<', '\'', '"', '$', '`']),
        "a checked command is plain words: {command}"
    );
    let out = Command::new(env!("CARGO_BIN_EXE_appell"))
        .args(&words[1..])
        .current_dir(dir)
        .output()
        .expect("runs");
    (
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn every_documented_output_is_what_the_command_gives() {
    let mut all = Vec::new();
    for doc in documents() {
        let text = std::fs::read_to_string(root().join(&doc)).unwrap();
        all.extend(blocks(&doc, &text));
    }
    let unmarked: Vec<String> = all
        .iter()
        .filter(|b| b.marker.is_none())
        .map(|b| format!("{}:{}", b.doc, b.line))
        .collect();
    assert!(
        unmarked.is_empty(),
        "output blocks without `<!-- output of: appell ... -->` or `<!-- not checked: why -->` above them: {}",
        unmarked.join(", ")
    );
    let checked: Vec<&Block> = all
        .iter()
        .filter(|b| matches!(b.marker, Some(Marker::Output(_))))
        .collect();
    assert!(checked.len() >= 5, "{} checked blocks", checked.len());
    let dir = scratch();
    let mut problems = Vec::new();
    for b in checked {
        let Some(Marker::Output(cmd)) = &b.marker else {
            unreachable!()
        };
        let (stdout, stderr) = run(cmd, dir.path());
        let found = matches(&b.text, &format!("{stderr}{stdout}"))
            .or_else(|_| matches(&b.text, &format!("{stdout}{stderr}")));
        if let Err(piece) = found {
            problems.push(format!(
                "{}:{} `{cmd}`: not in its output:\n  {}\n--- the output ---\n{stderr}{stdout}",
                b.doc,
                b.line,
                piece.join("\n  ")
            ));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n\n"));
}

#[test]
fn the_matching_rules_find_what_they_should() {
    let exp = |s: &str| s.lines().map(str::to_owned).collect::<Vec<_>>();
    let out = "a\nb 1.0\nc\nd\ne long tail\n";
    assert!(matches(&exp("a\nb 1.0\n...\nd\ne long ..."), out).is_ok());
    assert!(matches(&exp("b 1.0\nc"), out).is_ok());
    // Out of order, a changed number, lines that are not consecutive: each fails.
    assert!(matches(&exp("d\n...\na"), out).is_err());
    assert!(matches(&exp("b 1.1"), out).is_err());
    assert!(matches(&exp("a\nc"), out).is_err());
    assert_eq!(
        marker("<!-- output of: appell fit x --rig y -->"),
        Some(Marker::Output("appell fit x --rig y".into()))
    );
    assert_eq!(
        marker("<!-- not checked: prose -->"),
        Some(Marker::NotChecked)
    );
    let doc = "<!-- output of: appell simulate s.toml -->\n```text\nx\n```\n\n```text\ny\n```\n";
    let b = blocks("d.md", doc);
    assert_eq!(b.len(), 2);
    assert_eq!(
        b[0].marker,
        Some(Marker::Output("appell simulate s.toml".into()))
    );
    assert_eq!(b[0].text, vec!["x".to_owned()]);
    assert_eq!(b[1].marker, None);
}
