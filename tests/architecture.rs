//! The floor plan holds: no module imports one that imports it back, and the
//! library's top-level modules only import the layers below them
//! (docs/ARCHITECTURE.md draws them).
//!
//! Reads the sources as text: every `crate::…` and `super::…` path in a file
//! is an import of the module file it names (a `mod.rs` also depends on the
//! children it declares), so a cycle through a parent module's re-exports
//! counts as well.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The library's top-level modules, lowest layer first; a module may import
/// only modules of its own or a lower layer.
const LAYERS: &[&[&str]] = &[
    &["math", "error", "parallel"],
    &["cloth", "context"],
    &["forces", "collision"],
    &["integrators"],
    &["solver"],
    &["simulation", "metrics", "export"],
    &["rapier"],
    &["scenes"],
    &["cli", "viewer"],
];

/// Module path (relative to `src`, without extension) of every library file.
fn library_files() -> BTreeMap<String, PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                if path.file_name().unwrap() != "bin" {
                    walk(&path, out);
                }
            } else if path.extension().is_some_and(|e| e == "rs") {
                out.push(path);
            }
        }
    }
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    walk(&src, &mut files);
    files
        .into_iter()
        .filter_map(|p| {
            let rel = p.strip_prefix(&src).unwrap().with_extension("");
            let mut parts: Vec<String> = rel
                .components()
                .map(|c| c.as_os_str().to_string_lossy().into_owned())
                .collect();
            if parts.last().is_some_and(|l| l == "mod") {
                parts.pop();
            }
            if parts == ["lib"] {
                return None; // the root only declares and re-exports
            }
            Some((parts.join("::"), p))
        })
        .collect()
}

/// Text without comments (line and doc comments), so prose naming a path is
/// no import, and without the unit-test module at the end of a file (its
/// `super` is the file itself). A test-only item before it is code like any
/// other: cut at the first `#[cfg(test)]`, `grid_sweep.rs` (whose imports
/// began with one) hid a cycle with `grid_leftover.rs`.
fn code_of(text: &str) -> String {
    let text = text.split("#[cfg(test)]\nmod tests").next().unwrap_or(text);
    text.lines()
        .map(|l| match l.find("//") {
            Some(i) => &l[..i],
            None => l,
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// The modules a file's code names, resolved to the longest module path that exists.
fn imports(module: &str, code: &str, modules: &BTreeMap<String, PathBuf>) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    let here: Vec<&str> = module.split("::").collect();
    // Paths: `crate::a::b`, `super::a`, and grouped uses `crate::a::{b, c::d}`.
    let bytes = code.as_bytes();
    let is_ident = |c: u8| c.is_ascii_alphanumeric() || c == b'_';
    let mut i = 0;
    while i < bytes.len() {
        if !code.is_char_boundary(i) {
            i += 1;
            continue;
        }
        let rest = &code[i..];
        let start_ok = i == 0 || !is_ident(bytes[i - 1]) && bytes[i - 1] != b':';
        let (base, skip): (Vec<&str>, usize) = if start_ok && rest.starts_with("crate::") {
            (Vec::new(), "crate::".len())
        } else if start_ok && rest.starts_with("super::") {
            // `super` of module `a::b` is `a`, whether it is a/b.rs or a/b/mod.rs.
            let mut b = here.clone();
            let mut s = 0;
            let mut r = rest;
            while r.starts_with("super::") {
                b.pop();
                s += "super::".len();
                r = &r["super::".len()..];
            }
            (b, s)
        } else {
            i += 1;
            continue;
        };
        // Read the path that follows, expanding one level of braces.
        let tail = &code[i + skip..];
        let end = tail
            .find(|c: char| {
                !(c.is_alphanumeric()
                    || c == '_'
                    || c == ':'
                    || c == '{'
                    || c == '}'
                    || c == ','
                    || c == ' '
                    || c == '\n')
            })
            .unwrap_or(tail.len());
        let path = &tail[..end];
        let mut candidates = Vec::new();
        if let Some(open) = path.find('{') {
            let prefix = &path[..open];
            let close = path.rfind('}').unwrap_or(path.len());
            for item in path[open + 1..close].split(',') {
                candidates.push(format!("{prefix}{}", item.trim()));
            }
        } else {
            candidates.push(path.split_whitespace().next().unwrap_or("").to_string());
        }
        for c in candidates {
            let mut segs: Vec<String> = base.iter().map(|s| s.to_string()).collect();
            segs.extend(c.split("::").filter(|s| !s.is_empty()).map(str::to_string));
            while !segs.is_empty() {
                let key = segs.join("::");
                if modules.contains_key(&key) {
                    if key != module {
                        out.insert(key);
                    }
                    break;
                }
                segs.pop();
            }
        }
        i += skip;
    }
    out
}

fn graph() -> BTreeMap<String, BTreeSet<String>> {
    let modules = library_files();
    let mut g = BTreeMap::new();
    for (module, path) in &modules {
        let is_mod_rs = path.file_name().unwrap() == "mod.rs";
        let code = code_of(&std::fs::read_to_string(path).unwrap());
        let mut deps = imports(module, &code, &modules);
        if is_mod_rs {
            // A parent depends on the children it declares.
            for line in code.lines() {
                let l = line.trim();
                let l = l
                    .strip_prefix("pub(crate) ")
                    .or_else(|| l.strip_prefix("pub "))
                    .unwrap_or(l);
                if let Some(name) = l.strip_prefix("mod ").and_then(|r| r.strip_suffix(';')) {
                    deps.insert(format!("{module}::{}", name.trim()));
                }
            }
        }
        g.insert(module.clone(), deps);
    }
    g
}

#[test]
fn no_module_imports_one_that_imports_it_back() {
    let g = graph();
    // Tarjan-free: a module is on a cycle when it reaches itself.
    let mut cycles = Vec::new();
    for start in g.keys() {
        let mut stack: Vec<(String, Vec<String>)> = vec![(start.clone(), vec![start.clone()])];
        let mut seen = BTreeSet::new();
        while let Some((m, path)) = stack.pop() {
            for d in g.get(&m).into_iter().flatten() {
                if d == start {
                    let mut p = path.clone();
                    p.push(d.clone());
                    cycles.push(p.join(" -> "));
                } else if seen.insert(d.clone()) {
                    let mut p = path.clone();
                    p.push(d.clone());
                    stack.push((d.clone(), p));
                }
            }
        }
    }
    cycles.sort_by_key(|c| c.len());
    cycles.dedup();
    assert!(cycles.is_empty(), "import cycles:\n{}", cycles.join("\n"));
}

#[test]
fn top_level_modules_import_only_lower_layers() {
    let layer_of = |m: &str| {
        let top = m.split("::").next().unwrap();
        LAYERS.iter().position(|l| l.contains(&top))
    };
    let g = graph();
    let mut wrong = Vec::new();
    for (m, deps) in &g {
        let Some(lm) = layer_of(m) else {
            wrong.push(format!("{m} is in no layer of docs/ARCHITECTURE.md"));
            continue;
        };
        for d in deps {
            let ld = layer_of(d).unwrap_or(usize::MAX);
            if ld > lm {
                wrong.push(format!("{m} (layer {lm}) imports {d} (layer {ld})"));
            }
        }
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

#[test]
fn the_checker_sees_a_cycle() {
    // The reader itself: a parent re-exporting a child that imports it back.
    let mut modules = BTreeMap::new();
    modules.insert("a".to_string(), PathBuf::from("a/mod.rs"));
    modules.insert("a::b".to_string(), PathBuf::from("a/b.rs"));
    modules.insert("c".to_string(), PathBuf::from("c.rs"));
    let b = imports("a::b", "use super::{X, Y};\nuse crate::c::Z;", &modules);
    assert_eq!(b, BTreeSet::from(["a".to_string(), "c".to_string()]));
    let c = imports("c", "fn f() { crate::a::b::g(); }", &modules);
    assert_eq!(c, BTreeSet::from(["a::b".to_string()]));
    // A test-only import before the code does not hide the code after it;
    // the unit-test module at the end is left out.
    let text = "#[cfg(test)]\nuse crate::c::T;\nuse crate::a::b::U;\n#[cfg(test)]\nmod tests {\n    use crate::c::V;\n}\n";
    let code = code_of(text);
    assert!(code.contains("crate::a::b::U") && !code.contains("crate::c::V"));
}
