//! The layering of src/ (docs/architecture.md): the top-level rooms import
//! one way, and no two files import each other, directly or round a longer
//! loop. Read from the source text, so a new `use` that breaks either rule
//! fails here with the files named.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// What each room of the library may import (anything not listed is
/// refused). The tool (src/bin) may use everything and is not checked.
const MAY_IMPORT: &[(&str, &[&str])] = &[
    ("geometry", &[]),
    ("scene", &["geometry"]),
    ("render", &["scene", "geometry"]),
    ("engine", &["cluster", "render", "scene", "geometry"]),
    (
        "device",
        &["engine", "cluster", "render", "scene", "geometry"],
    ),
    ("capi", &["device", "engine", "render", "scene", "geometry"]),
    ("data", &["scene", "geometry"]),
    ("cave", &["data", "scene", "geometry"]),
    ("output", &["cave", "render", "scene", "geometry"]),
    ("cluster", &["render", "scene", "geometry"]),
];

type Module = Vec<String>;

/// Every library source file by its module path (`render::gpu` for
/// src/render/gpu/mod.rs), with its text less comments and unit tests.
fn sources(root: &Path) -> BTreeMap<Module, String> {
    fn walk(dir: &Path, root: &Path, out: &mut BTreeMap<Module, String>) {
        for entry in std::fs::read_dir(dir).expect("src/ is readable") {
            let path = entry.expect("a directory entry").path();
            if path.is_dir() {
                if path.file_name().is_some_and(|n| n != "bin") {
                    walk(&path, root, out);
                }
                continue;
            }
            if path.extension().is_none_or(|e| e != "rs") {
                continue;
            }
            let rel = path
                .strip_prefix(root)
                .expect("under src/")
                .with_extension("");
            let mut module: Module = rel
                .iter()
                .map(|s| s.to_string_lossy().into_owned())
                .collect();
            if matches!(module.last().map(String::as_str), Some("mod" | "lib")) {
                module.pop();
            }
            let text = std::fs::read_to_string(&path).expect("a readable source file");
            out.insert(module, code_only(&text));
        }
    }
    let mut out = BTreeMap::new();
    walk(root, root, &mut out);
    out
}

/// The text without `//` comments and without a trailing unit-test module.
fn code_only(text: &str) -> String {
    let mut code: String = text
        .lines()
        .map(|l| l.split_once("//").map_or(l, |(code, _)| code))
        .collect::<Vec<_>>()
        .join("\n");
    if let Some(at) = code.find("#[cfg(test)]\nmod tests") {
        code.truncate(at);
    }
    code
}

/// `use a::{b, c::{d, e}}` as the paths a::b, a::c::d, a::c::e.
fn expand(tree: &str) -> Vec<String> {
    let Some(open) = tree.find('{') else {
        return vec![tree.to_owned()];
    };
    let (prefix, rest) = tree.split_at(open);
    let inner = &rest[1..rest.len() - 1];
    let (mut parts, mut depth, mut start) = (Vec::new(), 0, 0);
    for (i, c) in inner.char_indices() {
        match c {
            '{' => depth += 1,
            '}' => depth -= 1,
            ',' if depth == 0 => {
                parts.push(&inner[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    parts.push(&inner[start..]);
    parts
        .into_iter()
        .filter(|p| !p.is_empty())
        .flat_map(|p| expand(&format!("{prefix}{p}")))
        .collect()
}

/// The `use` trees of a file, whitespace removed, `as` renames dropped.
fn use_paths(code: &str, public_only: bool) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = code;
    while let Some(at) = rest.find("use ") {
        let before = &rest[..at];
        let word_start = at == 0 || !before.ends_with(|c: char| c.is_alphanumeric() || c == '_');
        let Some(end) = rest[at..].find(';') else {
            break;
        };
        let stmt = &rest[at + 4..at + end];
        let public = before.trim_end().ends_with("pub") || before.trim_end().ends_with(')');
        rest = &rest[at + end..];
        if !word_start || (public_only && !public) {
            continue;
        }
        let tree: String = stmt.split_whitespace().collect::<Vec<_>>().join(" ");
        let tree = tree.replace(" as ", "@").replace(' ', "");
        out.extend(
            expand(&tree)
                .into_iter()
                .map(|p| p.split('@').next().unwrap_or_default().to_owned()),
        );
    }
    out
}

struct Tree {
    files: BTreeMap<Module, String>,
}

impl Tree {
    /// The file a path names, following `pub use` re-exports.
    fn resolve(&self, path: &[String], depth: usize) -> Option<Module> {
        for n in (0..=path.len()).rev() {
            let module = path[..n].to_vec();
            let Some(code) = self.files.get(&module) else {
                continue;
            };
            if n < path.len() && depth < 8 {
                let item = &path[n];
                for exported in use_paths(code, true) {
                    let segs: Vec<&str> = exported.split("::").collect();
                    if segs.last() == Some(&item.as_str()) || segs.last() == Some(&"*") {
                        let target = self.absolute(&module, &segs);
                        let mut full = target.clone();
                        if segs.last() != Some(&"*") {
                            full.truncate(full.len().saturating_sub(1));
                        }
                        full.push(item.clone());
                        if let Some(m) = self.resolve(&full, depth + 1) {
                            if m != module {
                                return Some(m);
                            }
                        }
                    }
                }
            }
            return Some(module);
        }
        None
    }

    /// A path of `module`'s text as a path from the crate root, or empty
    /// where it names another crate.
    fn absolute(&self, module: &Module, segs: &[&str]) -> Module {
        let mut out = module.clone();
        let mut segs = segs;
        match segs.first() {
            Some(&"crate") => {
                out.clear();
                segs = &segs[1..];
            }
            Some(&"self") => segs = &segs[1..],
            Some(&"super") => {
                while segs.first() == Some(&"super") {
                    out.pop();
                    segs = &segs[1..];
                }
            }
            // `pub use child::X` in a module names its own child.
            Some(first)
                if self
                    .files
                    .contains_key(&[module.as_slice(), &[first.to_string()]].concat()) => {}
            _ => return Vec::new(),
        }
        out.extend(segs.iter().map(|s| s.to_string()));
        out
    }

    /// Which files each file imports (imports of its own ancestors, the
    /// modules that declare it, are not counted).
    fn edges(&self) -> BTreeMap<Module, BTreeSet<Module>> {
        let mut edges = BTreeMap::new();
        for (module, code) in &self.files {
            let mut to = BTreeSet::new();
            let mut paths = use_paths(code, false);
            // Paths written out in code: crate::a::b.
            for (at, _) in code.match_indices("crate::") {
                let tail: String = code[at..]
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_' || *c == ':')
                    .collect();
                paths.push(tail.trim_end_matches(':').to_owned());
            }
            for p in paths {
                let segs: Vec<&str> = p.split("::").collect();
                let abs = self.absolute(module, &segs);
                if abs.is_empty() {
                    continue;
                }
                if let Some(target) = self.resolve(&abs, 0) {
                    let ancestor = |a: &Module, b: &Module| a.len() < b.len() && b.starts_with(a);
                    if target != *module && !ancestor(&target, module) && !ancestor(module, &target)
                    {
                        to.insert(target);
                    }
                }
            }
            edges.insert(module.clone(), to);
        }
        edges
    }
}

fn tree() -> Tree {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("src");
    Tree {
        files: sources(&root),
    }
}

fn name(m: &Module) -> String {
    if m.is_empty() {
        "lib".into()
    } else {
        m.join("/")
    }
}

#[test]
fn rooms_import_one_way() {
    let tree = tree();
    let allowed: BTreeMap<&str, &[&str]> = MAY_IMPORT.iter().copied().collect();
    let mut wrong = Vec::new();
    for (from, to) in tree.edges() {
        let Some(room) = from.first() else { continue };
        let may = allowed
            .get(room.as_str())
            .unwrap_or_else(|| panic!("src/{room} is not a room MAY_IMPORT knows"));
        for t in to {
            match t.first() {
                Some(other) if other != room && !may.contains(&other.as_str()) => {
                    wrong.push(format!("{} -> {}", name(&from), name(&t)))
                }
                _ => {}
            }
        }
    }
    assert!(
        wrong.is_empty(),
        "imports against the layering:\n{}",
        wrong.join("\n")
    );
}

#[test]
fn no_file_imports_a_file_that_imports_it() {
    let edges = tree().edges();
    // Tarjan's strongly connected components: any of more than one file
    // is a loop of imports.
    struct State<'a> {
        edges: &'a BTreeMap<Module, BTreeSet<Module>>,
        index: BTreeMap<&'a Module, usize>,
        low: BTreeMap<&'a Module, usize>,
        stack: Vec<&'a Module>,
        loops: Vec<Vec<String>>,
    }
    fn visit<'a>(s: &mut State<'a>, v: &'a Module) {
        let i = s.index.len();
        s.index.insert(v, i);
        s.low.insert(v, i);
        s.stack.push(v);
        for w in &s.edges[v] {
            if !s.index.contains_key(w) {
                visit(s, w);
                let lw = s.low[w];
                let lv = s.low.get_mut(v).expect("visited");
                *lv = (*lv).min(lw);
            } else if s.stack.contains(&w) {
                let iw = s.index[w];
                let lv = s.low.get_mut(v).expect("visited");
                *lv = (*lv).min(iw);
            }
        }
        if s.low[v] == s.index[v] {
            let mut component = Vec::new();
            while let Some(w) = s.stack.pop() {
                component.push(name(w));
                if w == v {
                    break;
                }
            }
            if component.len() > 1 {
                component.sort();
                s.loops.push(component);
            }
        }
    }
    let mut s = State {
        edges: &edges,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        loops: Vec::new(),
    };
    for v in edges.keys() {
        if !s.index.contains_key(v) {
            visit(&mut s, v);
        }
    }
    let described: Vec<String> = s.loops.iter().map(|l| l.join(", ")).collect();
    assert!(
        described.is_empty(),
        "files that import each other (round a loop):\n{}",
        described.join("\n")
    );
}

#[test]
fn the_checker_sees_a_loop_and_a_wrong_way_import() {
    // The parser itself, on a made-up tree: a <-> b through a re-export,
    // and a room that imports upwards.
    let mut files = BTreeMap::new();
    let m = |p: &str| p.split('/').map(String::from).collect::<Module>();
    files.insert(
        m("render"),
        "pub mod a;\npub mod b;\npub use a::Thing;\n".to_owned(),
    );
    files.insert(
        m("render/a"),
        "use super::b::{Other, more::{X}};\npub struct Thing;".to_owned(),
    );
    files.insert(
        m("render/b"),
        "use crate::render::Thing;\nuse crate::device::X;".to_owned(),
    );
    files.insert(m("device"), "pub struct X;".to_owned());
    let edges = Tree { files }.edges();
    assert!(edges[&m("render/a")].contains(&m("render/b")));
    assert!(
        edges[&m("render/b")].contains(&m("render/a")),
        "the re-export is followed"
    );
    assert!(edges[&m("render/b")].contains(&m("device")));
}
