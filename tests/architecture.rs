//! The layers of `src/`, written once in ARCHITECTURE.md, hold: each module
//! imports only from its own layer or from layers below it, and no two
//! folders of one layer import each other. A failure names the file, the
//! line and the import.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

mod common;

/// The layers, top to bottom, as the block after the line
/// `<!-- layers, top to bottom -->` in ARCHITECTURE.md lists them: one a
/// line, the module first.
fn layers() -> Vec<String> {
    let text = std::fs::read_to_string(common::root().join("ARCHITECTURE.md"))
        .expect("ARCHITECTURE.md is readable");
    let after = text
        .split_once("<!-- layers, top to bottom -->")
        .expect("ARCHITECTURE.md marks its layer list")
        .1;
    let block = after
        .split("```")
        .nth(1)
        .expect("the layer list is a fenced block");
    block
        .lines()
        .filter_map(|line| line.split_whitespace().next())
        .map(|module| {
            module
                .trim_end_matches('/')
                .trim_end_matches(".rs")
                .to_owned()
        })
        .collect()
}

/// One `crate::a::b` path named in a source file.
#[derive(Debug)]
struct Import {
    file: PathBuf,
    line: usize,
    /// The path's segments after `crate::` (or `cablecell::` in the binary).
    path: Vec<String>,
}

/// Every `.rs` file under `dir`.
fn sources(dir: &Path) -> Vec<PathBuf> {
    let mut files = Vec::new();
    for entry in std::fs::read_dir(dir).expect("src/ is readable") {
        let path = entry.expect("a directory entry").path();
        if path.is_dir() {
            files.extend(sources(&path));
        } else if path.extension().is_some_and(|ext| ext == "rs") {
            files.push(path);
        }
    }
    files
}

/// The source without its comments, line breaks kept.
fn without_comments(text: &str) -> String {
    text.lines()
        .map(|line| match line.find("//") {
            Some(at) => &line[..at],
            None => line,
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// The paths that `text` names from the crate's root, `root` being `crate`
/// in the library and `cablecell` in the binary. A grouped import
/// (`crate::{a::x, b}`) names each of its members.
fn imports(file: &Path, text: &str, root: &str) -> Vec<Import> {
    let code = without_comments(text);
    let prefix = format!("{root}::");
    let mut found = Vec::new();
    let mut from = 0;
    while let Some(at) = code[from..].find(&prefix) {
        let start = from + at;
        from = start + prefix.len();
        let before = code[..start].chars().next_back();
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
            continue;
        }
        let line = code[..start].matches('\n').count() + 1;
        let rest = &code[from..];
        if let Some(group) = rest.strip_prefix('{') {
            let end = group.find('}').unwrap_or(group.len());
            for member in group[..end].split(',') {
                let path = segments(member);
                if !path.is_empty() {
                    found.push(Import {
                        file: file.to_owned(),
                        line,
                        path,
                    });
                }
            }
        } else {
            found.push(Import {
                file: file.to_owned(),
                line,
                path: segments(rest),
            });
        }
    }
    found
}

/// The leading `a::b::c` of `text`.
fn segments(text: &str) -> Vec<String> {
    let text = text.trim_start();
    let end = text
        .find(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':'))
        .unwrap_or(text.len());
    text[..end]
        .split("::")
        .filter(|segment| !segment.is_empty())
        .map(str::to_owned)
        .collect()
}

/// The module a file of `src/` belongs to, as `[top, folder]`: `cli` for
/// the binary; the folder is the second level where there is one.
fn module_of(src: &Path, file: &Path) -> Vec<String> {
    let relative = file.strip_prefix(src).expect("a file under src/");
    let mut parts: Vec<String> = relative
        .iter()
        .map(|part| part.to_string_lossy().trim_end_matches(".rs").to_owned())
        .collect();
    if parts[0] == "main" {
        return vec!["cli".to_owned()];
    }
    if parts.last().is_some_and(|last| last == "mod") {
        parts.pop();
    }
    parts.truncate(2);
    parts
}

fn all_imports() -> (PathBuf, Vec<(Vec<String>, Import)>) {
    let src = common::root().join("src");
    let mut all = Vec::new();
    for file in sources(&src) {
        let text = std::fs::read_to_string(&file).expect("a readable source file");
        let from = module_of(&src, &file);
        let root = if from[0] == "cli" {
            "cablecell"
        } else {
            "crate"
        };
        for import in imports(&file, &text, root) {
            all.push((from.clone(), import));
        }
    }
    (src, all)
}

fn place(src: &Path, import: &Import) -> String {
    format!(
        "{}:{}: {}",
        import
            .file
            .strip_prefix(src.parent().expect("src/ has a parent"))
            .unwrap_or(&import.file)
            .display(),
        import.line,
        import.path.join("::")
    )
}

#[test]
fn every_import_points_down_the_layers() {
    let layers = layers();
    assert!(
        layers.len() >= 10,
        "ARCHITECTURE.md lists the layers: {layers:?}"
    );
    let rank = |module: &str| layers.iter().position(|layer| layer == module);
    let (src, all) = all_imports();
    assert!(all.len() > 100, "the parser finds the crate's imports");
    let mut wrong = Vec::new();
    for (from, import) in &all {
        let Some(to) = import.path.first() else {
            continue;
        };
        if to == "cli" && from[0] == "cli" {
            continue;
        }
        let (Some(from_rank), Some(to_rank)) = (rank(&from[0]), rank(to)) else {
            wrong.push(format!(
                "{}: {} or {} is not in ARCHITECTURE.md's layer list",
                place(&src, import),
                from[0],
                to
            ));
            continue;
        };
        if to_rank < from_rank {
            wrong.push(format!(
                "{}: {} imports {}, a layer above it",
                place(&src, import),
                from[0],
                to
            ));
        }
    }
    assert!(
        wrong.is_empty(),
        "imports up the layers:\n{}",
        wrong.join("\n")
    );
}

#[test]
fn no_two_folders_import_each_other() {
    let (src, all) = all_imports();
    // folder -> folder it imports -> the first import that does it
    let mut edges: BTreeMap<String, BTreeMap<String, String>> = BTreeMap::new();
    for (from, import) in &all {
        let folder = |path: &[String]| path.len() >= 2 && path[1].starts_with(char::is_lowercase);
        if !folder(&import.path) || !folder(from) || import.path[0] != from[0] {
            continue;
        }
        let (a, b) = (from.join("/"), import.path[..2].join("/"));
        if a != b {
            edges
                .entry(a)
                .or_default()
                .entry(b)
                .or_insert_with(|| place(&src, import));
        }
    }
    let mut pairs = BTreeSet::new();
    let mut cycles = Vec::new();
    for (a, targets) in &edges {
        for (b, there) in targets {
            if let Some(back) = edges.get(b).and_then(|of_b| of_b.get(a))
                && pairs.insert(if a < b { (a, b) } else { (b, a) })
            {
                cycles.push(format!("{a} ↔ {b}: {there} and {back}"));
            }
        }
    }
    assert!(
        cycles.is_empty(),
        "folders that import each other:\n{}",
        cycles.join("\n")
    );
}

#[test]
fn the_parser_sees_grouped_and_nested_imports() {
    let text = "use crate::{hw::arm::Arm, sim::world};\n// use crate::cli::x;\nlet x = crate::geometry::Pose::default();\n";
    let paths: Vec<String> = imports(Path::new("x.rs"), text, "crate")
        .iter()
        .map(|import| format!("{}@{}", import.path.join("::"), import.line))
        .collect();
    assert_eq!(
        paths,
        [
            "hw::arm::Arm@1",
            "sim::world@1",
            "geometry::Pose::default@3"
        ]
    );
}

/// Most a file may hold before its test module: more says that it mixes
/// concerns, unless its first comment says why it is long ("long because").
const MAX_LINES_BEFORE_TESTS: usize = 700;

#[test]
fn no_file_is_long_unless_it_says_why() {
    let src = common::root().join("src");
    let mut long = Vec::new();
    for file in sources(&src) {
        let text = std::fs::read_to_string(&file).expect("a readable source file");
        let lines = text
            .lines()
            .position(|line| line.trim() == "#[cfg(test)]")
            .unwrap_or_else(|| text.lines().count());
        let first_comment: String = text
            .lines()
            .take_while(|line| line.starts_with("//"))
            .collect();
        if lines > MAX_LINES_BEFORE_TESTS && !first_comment.contains("long because") {
            long.push(format!("{}: {lines} lines", file.display()));
        }
    }
    assert!(
        long.is_empty(),
        "files over {MAX_LINES_BEFORE_TESTS} lines before their tests:\n{}",
        long.join("\n")
    );
}
