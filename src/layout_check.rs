//! Test only: the top-level modules use each other in the one direction lib.rs's map documents.
//!
//! The graph is read from the source text: module A uses module B when a file of A (`src/A.rs` or
//! anything under `src/A/`) names a `crate::B` path, comments left out. lib.rs lists the modules
//! in its "Dependencies" block, users before what they use; every edge must point down that
//! list, which also makes the graph acyclic, and every module must be listed once. The binary's
//! `src/cli/` and `src/main.rs` are not part of the library and not checked.
//!
//! The file maps are checked against the tree: lib.rs's map and README's layout section each
//! hold a block that names every folder and `.rs` file under `src/` once (a folder's `mod.rs` is
//! the folder's line), nested by indentation, and nothing that is not there.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// `module -> (module it uses -> a file where it does)`.
type Graph = BTreeMap<String, BTreeMap<String, String>>;

/// The heading above the file map of lib.rs and of README's layout section.
const FILES_MARKER: &str = "Every file of src/";

/// The text with `//` comments (doc comments included) removed, string literals kept.
fn strip_comments(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for line in text.lines() {
        let mut in_str = false;
        let mut prev = '\0';
        let mut cut = line.len();
        let b: Vec<(usize, char)> = line.char_indices().collect();
        for (k, &(i, c)) in b.iter().enumerate() {
            if c == '"' && prev != '\\' {
                in_str = !in_str;
            }
            if !in_str && c == '/' && b.get(k + 1).map(|x| x.1) == Some('/') {
                cut = i;
                break;
            }
            prev = c;
        }
        out.push_str(&line[..cut]);
        out.push('\n');
    }
    out
}

/// The top-level modules a text names through `crate::NAME` or `crate::{NAME, ...}`.
fn crate_paths(text: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    let text = strip_comments(text);
    let mut rest = text.as_str();
    while let Some(i) = rest.find("crate::") {
        // `crate::` preceded by an identifier character is another path (`allanscope_crate::`).
        let before = rest[..i].chars().next_back();
        rest = &rest[i + "crate::".len()..];
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == ':') {
            continue;
        }
        if let Some(group) = rest.strip_prefix('{') {
            let end = group.find('}').unwrap_or(group.len());
            for item in group[..end].split(',') {
                let name: String = item
                    .trim()
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect();
                if !name.is_empty() {
                    out.insert(name);
                }
            }
        } else {
            let name: String = rest
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            if !name.is_empty() {
                out.insert(name);
            }
        }
    }
    out
}

fn rust_files(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The library's top-level modules under `src` and the graph of their uses.
fn module_graph(src: &Path) -> (BTreeSet<String>, Graph) {
    let mut modules = BTreeSet::new();
    for e in std::fs::read_dir(src).expect("src/").flatten() {
        let name = e.file_name().to_string_lossy().to_string();
        let p = e.path();
        let m = if p.is_dir() {
            name
        } else if let Some(stem) = name.strip_suffix(".rs") {
            stem.to_string()
        } else {
            continue;
        };
        if !matches!(m.as_str(), "lib" | "main" | "cli" | "layout_check") {
            modules.insert(m);
        }
    }
    let mut graph = Graph::new();
    for m in &modules {
        let mut files = Vec::new();
        rust_files(&src.join(m), &mut files);
        let file = src.join(format!("{m}.rs"));
        if file.exists() {
            files.push(file);
        }
        files.sort();
        for f in files {
            let text = std::fs::read_to_string(&f).expect("source file");
            for used in crate_paths(&text) {
                if used != *m && modules.contains(&used) {
                    graph
                        .entry(m.clone())
                        .or_default()
                        .entry(used)
                        .or_insert_with(|| f.display().to_string());
                }
            }
        }
    }
    (modules, graph)
}

/// A cycle of the graph, as the modules along it, if there is one.
fn find_cycle(graph: &Graph) -> Option<Vec<String>> {
    fn visit(
        n: &str,
        graph: &Graph,
        state: &mut BTreeMap<String, u8>,
        path: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        match state.get(n) {
            Some(2) => return None,
            Some(1) => {
                let at = path.iter().position(|p| p == n).unwrap_or(0);
                let mut cycle = path[at..].to_vec();
                cycle.push(n.to_string());
                return Some(cycle);
            }
            _ => {}
        }
        state.insert(n.to_string(), 1);
        path.push(n.to_string());
        for next in graph.get(n).into_iter().flat_map(|e| e.keys()) {
            if let Some(c) = visit(next, graph, state, path) {
                return Some(c);
            }
        }
        path.pop();
        state.insert(n.to_string(), 2);
        None
    }
    let mut state = BTreeMap::new();
    for n in graph.keys() {
        if let Some(c) = visit(n, graph, &mut state, &mut Vec::new()) {
            return Some(c);
        }
    }
    None
}

/// The module order of lib.rs's "Dependencies" block: the words of the lines between
/// `Dependencies` and the end of that text block.
fn documented_order(lib_rs: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut inside = false;
    for line in lib_rs.lines() {
        let Some(doc) = line.strip_prefix("//!") else {
            continue;
        };
        if doc.contains("Dependencies (") {
            inside = true;
            continue;
        }
        if inside {
            if doc.trim() == "```" {
                break;
            }
            // `name: what it is` lines; the name may be indented under its user.
            if let Some((name, _)) = doc.split_once(':') {
                let name = name.trim();
                if !name.is_empty() && name.chars().all(|c| c.is_alphanumeric() || c == '_') {
                    out.push(name.to_string());
                }
            }
        }
    }
    out
}

/// Every problem of the layout: modules not listed or listed twice, uses that point up the
/// list (with a file that makes them), and a cycle.
fn layout_problems(src: &Path) -> Vec<String> {
    let lib = std::fs::read_to_string(src.join("lib.rs")).expect("lib.rs");
    let order = documented_order(&lib);
    let (modules, graph) = module_graph(src);
    let mut problems = Vec::new();
    let rank: BTreeMap<&str, usize> = order
        .iter()
        .enumerate()
        .map(|(i, m)| (m.as_str(), i))
        .collect();
    for m in &modules {
        match order.iter().filter(|o| *o == m).count() {
            0 => problems.push(format!("module `{m}` is not in lib.rs's dependency list")),
            1 => {}
            n => problems.push(format!("module `{m}` is listed {n} times in lib.rs")),
        }
    }
    for o in &order {
        if !modules.contains(o) {
            problems.push(format!(
                "lib.rs lists `{o}`, which is not a module under src/"
            ));
        }
    }
    for (a, uses) in &graph {
        for (b, file) in uses {
            if let (Some(ra), Some(rb)) = (rank.get(a.as_str()), rank.get(b.as_str())) {
                if rb <= ra {
                    problems.push(format!(
                        "`{a}` uses `{b}` ({file}), which lib.rs lists above it"
                    ));
                }
            }
        }
    }
    if let Some(c) = find_cycle(&graph) {
        problems.push(format!("import cycle: {}", c.join(" -> ")));
    }
    problems
}

/// The files and folders a tree block names: the lines of the ```` ```text ```` block that
/// follows the line holding `marker`, each `name.rs  role` or `name/  role`, nested two spaces a
/// level under its folder; other lines (a role running on) are passed over. Paths are relative
/// to `src/`, folders end in `/`.
fn documented_tree(text: &str, marker: &str, prefix: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut folders: Vec<String> = Vec::new();
    let mut state = 0; // 0: before the marker, 1: before the block, 2: inside it
    for line in text.lines() {
        let Some(line) = line.strip_prefix(prefix) else {
            continue;
        };
        // The space after a comment's `//!` is not indentation.
        let line = match prefix {
            "" => line,
            _ => line.strip_prefix(' ').unwrap_or(line),
        };
        match state {
            0 if line.contains(marker) => state = 1,
            1 if line.trim_start().starts_with("```") => state = 2,
            2 if line.trim_start().starts_with("```") => break,
            2 => {
                let indent = line.len() - line.trim_start().len();
                let Some(name) = line.split_whitespace().next() else {
                    continue;
                };
                let is_file = name.ends_with(".rs");
                let is_folder = name.ends_with('/') && name.len() > 1;
                if indent % 2 != 0 || !(is_file || is_folder) {
                    continue;
                }
                let depth = indent / 2;
                if depth > folders.len() {
                    continue;
                }
                folders.truncate(depth);
                out.push(format!("{}{name}", folders.concat()));
                if is_folder {
                    folders.push(name.to_string());
                }
            }
            _ => {}
        }
    }
    out
}

/// Every `.rs` file and every folder under `src` (relative, folders ending in `/`); a folder's
/// `mod.rs` is the folder's own line.
fn source_tree(src: &Path) -> BTreeSet<String> {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    let mut out = BTreeSet::new();
    for f in files {
        let rel = f
            .strip_prefix(src)
            .expect("under src")
            .to_string_lossy()
            .replace('\\', "/");
        let mut dir = String::new();
        let parts: Vec<&str> = rel.split('/').collect();
        for p in &parts[..parts.len() - 1] {
            dir.push_str(p);
            dir.push('/');
            out.insert(dir.clone());
        }
        if !rel.ends_with("/mod.rs") {
            out.insert(rel);
        }
    }
    out
}

/// What a tree block gets wrong against the sources: a file or folder it leaves out, one it
/// names that does not exist, one it names twice.
fn tree_problems(src: &Path, text: &str, marker: &str, prefix: &str, what: &str) -> Vec<String> {
    let listed = documented_tree(text, marker, prefix);
    let tree = source_tree(src);
    let mut problems = Vec::new();
    for t in &tree {
        if !listed.contains(t) {
            problems.push(format!("{what} leaves out src/{t}"));
        }
    }
    let mut seen = BTreeSet::new();
    for l in &listed {
        if !tree.contains(l) {
            problems.push(format!("{what} names src/{l}, which does not exist"));
        }
        if !seen.insert(l) {
            problems.push(format!("{what} names src/{l} twice"));
        }
    }
    problems
}

#[test]
fn the_library_layout_follows_the_documented_order() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let problems = layout_problems(&src);
    assert!(problems.is_empty(), "{}", problems.join("\n"));
    // The check sees the library: it lists at least the stages of the map.
    let (modules, graph) = module_graph(&src);
    for m in ["allan", "model", "gap", "sink", "pipeline", "analysis"] {
        assert!(modules.contains(m), "{m}");
    }
    assert!(graph["pipeline"].contains_key("analysis"));
    assert!(graph["analysis"].contains_key("allan"));
}

#[test]
fn a_use_against_the_order_or_a_cycle_is_found() {
    let dir = std::env::temp_dir().join(format!("allanscope-layout-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("b")).unwrap();
    let lib = "//! ```text\n//! Dependencies (users first):\n//! a: top\n//!   b: middle\n//! c: bottom\n//! ```\n";
    std::fs::write(dir.join("lib.rs"), lib).unwrap();
    std::fs::write(dir.join("a.rs"), "use crate::b::X;\nuse crate::{c, b};\n").unwrap();
    // A comment naming `crate::a` is not a use.
    std::fs::write(dir.join("b/mod.rs"), "// see crate::a\nuse crate::c::Y;\n").unwrap();
    std::fs::write(dir.join("c.rs"), "pub struct Y;\n").unwrap();
    assert_eq!(layout_problems(&dir), Vec::<String>::new());
    // c now uses a: against the order, and a cycle a -> b -> c -> a.
    std::fs::write(dir.join("c.rs"), "fn f() { crate::a::g() }\n").unwrap();
    let p = layout_problems(&dir);
    assert!(p.iter().any(|s| s.starts_with("`c` uses `a`")), "{p:?}");
    assert!(p.iter().any(|s| s.starts_with("import cycle:")), "{p:?}");
    // A module lib.rs does not list.
    std::fs::write(dir.join("d.rs"), "").unwrap();
    let p = layout_problems(&dir);
    assert!(p.iter().any(|s| s.contains("`d` is not in")), "{p:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// lib.rs's file map and README's layout name every file and folder of `src/` once, and
/// nothing else.
#[test]
fn the_maps_name_every_file() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let src = root.join("src");
    let lib = std::fs::read_to_string(src.join("lib.rs")).expect("lib.rs");
    let readme = std::fs::read_to_string(root.join("README.md")).expect("README.md");
    let mut problems = tree_problems(&src, &lib, FILES_MARKER, "//!", "lib.rs's map");
    problems.extend(tree_problems(
        &src,
        &readme,
        FILES_MARKER,
        "",
        "README's layout",
    ));
    assert!(problems.is_empty(), "{}", problems.join("\n"));
    // The check sees the tree: nested folders and their files.
    let tree = source_tree(&src);
    for p in [
        "frame/",
        "frame/descriptor/",
        "frame/descriptor/parse.rs",
        "lib.rs",
    ] {
        assert!(tree.contains(p), "{p}");
    }
}

#[test]
fn a_file_left_out_of_a_map_is_found() {
    let dir = std::env::temp_dir().join(format!("allanscope-tree-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("a/b")).unwrap();
    for f in [
        "lib.rs",
        "a/mod.rs",
        "a/x.rs",
        "a/b/mod.rs",
        "a/b/y.rs",
        "c.rs",
    ] {
        std::fs::write(dir.join(f), "").unwrap();
    }
    let map = format!(
        "{FILES_MARKER}\n```text\nlib.rs   the map\na/       a folder\n  x.rs   a file\n  b/     \
         nested\n    y.rs the file in it\n         a role running on\nc.rs     last\n```\n"
    );
    assert_eq!(
        tree_problems(&dir, &map, FILES_MARKER, "", "map"),
        Vec::<String>::new()
    );
    // y.rs at the wrong depth, c.rs left out, z.rs named but absent.
    let bad = map
        .replace("    y.rs", "  y.rs")
        .replace("c.rs     last", "z.rs     gone");
    let p = tree_problems(&dir, &bad, FILES_MARKER, "", "map");
    for want in [
        "map leaves out src/a/b/y.rs",
        "map leaves out src/c.rs",
        "map names src/a/y.rs, which does not exist",
        "map names src/z.rs, which does not exist",
    ] {
        assert!(p.iter().any(|s| s == want), "{want}: {p:?}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
