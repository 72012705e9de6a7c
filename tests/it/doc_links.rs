//! The repository holds its own reference: every relative link and every cited repository path
//! in README.md, docs/*.md and tests/data/README.md exists, none points outside the repository
//! (a `../shared` mention is allowed only in docs/development.md, as optional developer data),
//! and tests/data/README.md names every entry of tests/data.

use std::path::{Component, Path, PathBuf};

/// Backticked words that start with one of these are taken as repository paths and must exist.
const PREFIXES: [&str; 10] = [
    "src/",
    "tests/",
    "docs/",
    "scripts/",
    "configs/",
    "data/",
    "fuzz/",
    ".ci/",
    "examples/",
    "assets/",
];

/// The only file that may mention `../shared` (developer data beside a checkout).
const SHARED_ALLOWED: &str = "docs/development.md";

pub(crate) fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The documents checked, relative to the repository root.
pub(crate) fn documents() -> Vec<String> {
    let mut docs: Vec<String> = std::fs::read_dir(root().join("docs"))
        .expect("docs/ exists")
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "md"))
        .map(|p| format!("docs/{}", p.file_name().unwrap().to_string_lossy()))
        .collect();
    docs.sort();
    docs.insert(0, "README.md".to_owned());
    docs.push("tests/data/README.md".to_owned());
    docs
}

/// The text outside fenced code blocks (commands and outputs there are not citations).
fn prose(text: &str) -> String {
    let mut out = String::new();
    let mut fenced = false;
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if !fenced {
            out.push_str(line);
            out.push('\n');
        }
    }
    out
}

/// Targets of inline links `[text](target)`, without a title or a `#fragment`.
fn link_targets(text: &str) -> Vec<String> {
    let mut targets = Vec::new();
    let mut rest = text;
    while let Some(i) = rest.find("](") {
        let after = &rest[i + 2..];
        let Some(end) = after.find(')') else { break };
        let target = after[..end].trim().trim_matches(|c| c == '<' || c == '>');
        let target = target.split_whitespace().next().unwrap_or("");
        targets.push(target.split('#').next().unwrap_or("").to_owned());
        rest = &after[end..];
    }
    targets
}

/// Words of inline code spans that look like repository paths: they start with one of
/// [`PREFIXES`], have no glob or placeholder characters, and lose trailing punctuation and a
/// `:line` suffix.
fn cited_paths(text: &str) -> Vec<String> {
    text.split('`')
        .skip(1)
        .step_by(2)
        .flat_map(str::split_whitespace)
        .map(|w| {
            w.trim_start_matches('(')
                .trim_end_matches(['.', ',', ';', ':', ')'])
        })
        .filter(|w| PREFIXES.iter().any(|p| w.starts_with(p)))
        .filter(|w| !w.contains(['*', '?', '[', '{', '<']))
        .map(|w| w.split(':').next().unwrap().to_owned())
        .collect()
}

/// `path` with `.` and `..` resolved lexically (the target need not exist).
fn normalize(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            Component::ParentDir => {
                out.pop();
            }
            Component::CurDir => {}
            other => out.push(other),
        }
    }
    out
}

/// Every problem of one document, as readable lines.
fn problems_of(doc: &str) -> Vec<String> {
    let repo = root();
    let path = repo.join(doc);
    let Ok(text) = std::fs::read_to_string(&path) else {
        return vec![format!("{doc}: missing")];
    };
    let mut problems = Vec::new();
    if doc != SHARED_ALLOWED {
        for (n, line) in text.lines().enumerate() {
            if line.contains("../shared") {
                problems.push(format!(
                    "{doc}:{}: mentions ../shared, which is not part of the repository",
                    n + 1
                ));
            }
        }
    }
    let prose = prose(&text);
    let dir = path.parent().unwrap();
    for target in link_targets(&prose) {
        if target.is_empty()
            || target.starts_with("http://")
            || target.starts_with("https://")
            || target.starts_with("mailto:")
        {
            continue;
        }
        let resolved = normalize(&dir.join(&target));
        if !resolved.starts_with(&repo) {
            problems.push(format!("{doc}: link ({target}) leaves the repository"));
        } else if !resolved.exists() {
            problems.push(format!("{doc}: link ({target}) does not exist"));
        }
    }
    for cited in cited_paths(&prose) {
        if !repo.join(&cited).exists() {
            problems.push(format!("{doc}: `{cited}` does not exist"));
        }
    }
    problems
}

#[test]
fn every_link_and_cited_path_in_the_docs_exists() {
    let docs = documents();
    assert!(
        docs.len() >= 8,
        "README.md, docs/*.md and tests/data/README.md: {docs:?}"
    );
    let problems: Vec<String> = docs.iter().flat_map(|d| problems_of(d.as_str())).collect();
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn the_test_data_readme_names_every_entry_of_tests_data() {
    let dir = root().join("tests/data");
    let readme = std::fs::read_to_string(dir.join("README.md")).expect("tests/data/README.md");
    let mut missing = Vec::new();
    for entry in std::fs::read_dir(&dir).unwrap() {
        let entry = entry.unwrap();
        let name = entry.file_name().to_string_lossy().into_owned();
        if name == "README.md" {
            continue;
        }
        let named = readme.contains(&format!("`{name}`")) || readme.contains(&format!("`{name}/`"));
        if !named {
            missing.push(name);
        }
    }
    missing.sort();
    assert!(
        missing.is_empty(),
        "tests/data/README.md does not name: {}",
        missing.join(", ")
    );
}

#[test]
fn the_checks_find_what_they_look_for() {
    let text = "see [physics](physics.md#the-rig) and [web](https://example.org), \
                `src/model/forces.rs:12`, `appell fit tests/data/x.csv --rig configs/y.toml`, \
                `tests/data/rigid/*.csv` and `model::regions`.";
    assert_eq!(
        link_targets(text),
        ["physics.md", "https://example.org"].map(String::from)
    );
    assert_eq!(
        cited_paths(text),
        ["src/model/forces.rs", "tests/data/x.csv", "configs/y.toml"].map(String::from)
    );
    assert_eq!(prose("a\n```sh\n`src/x`\n```\nb\n"), "a\nb\n");
    assert_eq!(
        normalize(Path::new("/r/docs/../tests/data/README.md")),
        PathBuf::from("/r/tests/data/README.md")
    );
}

/// Folders the repository-wide check does not read: build output, version control, and the
/// fuzzer's corpus and its own build (outside the workspace), and the virtual environment
/// `scripts/checks/test_python.sh` makes (its packages are not the repository's).
const NOT_READ: [&str; 6] = [
    "target",
    ".git",
    ".venv",
    "fuzz/target",
    "fuzz/corpus",
    "fuzz/artifacts",
];

/// Words ending in `.md` that name no file: a Python attribute (`args.md`, the sweep's
/// `--md` option) and a document name a test gives its in-memory text.
const NOT_FILES: [&str; 2] = ["args.md", "d.md"];

/// Every text file of the repository (valid UTF-8, outside [`NOT_READ`]), relative to its root.
fn text_files(dir: &Path, out: &mut Vec<(String, String)>) {
    let root = root();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let rel = path
            .strip_prefix(&root)
            .unwrap()
            .to_string_lossy()
            .into_owned();
        if NOT_READ.contains(&rel.as_str()) {
            continue;
        }
        if path.is_dir() {
            text_files(&path, out);
        } else if let Ok(text) = std::fs::read_to_string(&path) {
            out.push((rel, text));
        }
    }
}

/// The `NAME.md` words of `text` not inside a path (no `/`, `.` or word character before them).
fn markdown_names(text: &str) -> Vec<&str> {
    let bytes = text.as_bytes();
    let word = |b: u8| b.is_ascii_alphanumeric() || b == b'_' || b == b'-';
    let mut out = Vec::new();
    for (at, _) in text.match_indices(".md") {
        let end = at + 3;
        if bytes.get(end).is_some_and(|&b| word(b)) {
            continue;
        }
        let mut start = at;
        while start > 0 && word(bytes[start - 1]) {
            start -= 1;
        }
        let before = start.checked_sub(1).map(|i| bytes[i]);
        if start < at && !before.is_some_and(|b| word(b) || b == b'/' || b == b'.') {
            out.push(&text[start..end]);
        }
    }
    out
}

/// Users have the repository alone: no tracked text names a Markdown file the repository lacks
/// (the project's shared notes stay beside a developer's checkout: the repository's own are
/// docs/physics.md and docs/formats.md), and only docs/development.md and this check mention
/// `../shared`.
#[test]
fn no_text_names_a_file_the_repository_lacks() {
    let mut files = Vec::new();
    text_files(&root(), &mut files);
    assert!(files.len() > 300, "{} text files", files.len());
    let names: std::collections::BTreeSet<String> = files
        .iter()
        .filter(|(rel, _)| rel.ends_with(".md"))
        .map(|(rel, _)| rel.rsplit('/').next().unwrap().to_owned())
        .collect();
    let mut problems = Vec::new();
    // This file names what it looks for.
    let this = "tests/it/doc_links.rs";
    for (rel, text) in files.iter().filter(|(rel, _)| rel != this) {
        for name in markdown_names(text) {
            if !names.contains(name) && !NOT_FILES.contains(&name) {
                problems.push(format!(
                    "{rel}: names {name}, which the repository does not hold"
                ));
            }
        }
        if rel != SHARED_ALLOWED && text.contains("../shared") {
            problems.push(format!(
                "{rel}: mentions ../shared, which is not part of the repository"
            ));
        }
    }
    problems.sort();
    problems.dedup();
    assert!(problems.is_empty(), "{}", problems.join("\n"));
    // The check finds what it looks for.
    assert_eq!(
        markdown_names("see PHYSICS.md, docs/physics.md"),
        ["PHYSICS.md"]
    );
    assert!(markdown_names("x.mdx and a.md5").is_empty());
}
