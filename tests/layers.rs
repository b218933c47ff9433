//! The architecture as a test: every `crate::`, `super::` and child-module
//! path in `src/` is read, and the build fails on an import that climbs a
//! layer or on an import cycle between files (ARCHITECTURE.md draws the
//! same graph).
//!
//! Layers, lowest first (a module may use only those listed for it):
//!
//! ```text
//! core                         errors, jobs, limits, rng, values, parallel driver
//! raster, geom, optim          core
//! inspect                      core, raster
//! pixel pattern tangle         core, raster, geom, optim, inspect
//! texture micro                (never one another)
//! api                          everything above (the request registry)
//! web                          api and below (the wasm boundary)
//! cli, bench                  the `filigree` binary (src/cli/main.rs is its
//!                              crate root): not read here, it may use
//!                              everything; the library cannot name it
//! ```
//!
//! Paths are resolved to files (`crate::geom::fft::Fft` → `src/geom/fft.rs`).
//! A `mod.rs`'s own paths into its children are its facade (`pub use
//! cells::Cell`), not a dependency, so they are not edges; a child's paths
//! into its parent (`super::X`) are.
use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::path::{Path, PathBuf};

const TOOLS: &[&str] = &["pixel", "pattern", "tangle", "texture", "micro"];

/// The modules `module` may use (besides itself).
fn allowed(module: &str) -> Option<Vec<&'static str>> {
    let shared = vec!["core", "raster", "geom", "optim", "inspect"];
    Some(match module {
        "core" => vec![],
        "raster" | "geom" | "optim" => vec!["core"],
        "inspect" => vec!["core", "raster"],
        m if TOOLS.contains(&m) => shared,
        "api" => {
            let mut v = shared;
            v.extend(TOOLS);
            v
        }
        "web" => vec!["api", "core", "raster"],
        "lib" => return None, // the crate root: anything
        other => {
            panic!("src/{other}: a module the layering test does not know; add it to `allowed`")
        }
    })
}

fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            // A nested crate (its own Cargo.toml) is not part of this one.
            if !p.join("Cargo.toml").exists() {
                rust_files(&p, out);
            }
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The code with comments, strings and char literals blanked out.
fn code_only(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = String::with_capacity(s.len());
    let mut i = 0;
    while i < b.len() {
        if b[i..].starts_with(b"//") {
            while i < b.len() && b[i] != b'\n' {
                i += 1;
            }
        } else if b[i..].starts_with(b"/*") {
            let mut depth = 0;
            while i < b.len() {
                if b[i..].starts_with(b"/*") {
                    depth += 1;
                    i += 2;
                } else if b[i..].starts_with(b"*/") {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    i += 1;
                }
            }
        } else if b[i] == b'r' && (b[i..].starts_with(b"r\"") || b[i..].starts_with(b"r#")) {
            // Raw string: r"…", r#"…"#, …
            let mut j = i + 1;
            let mut hashes = 0;
            while j < b.len() && b[j] == b'#' {
                hashes += 1;
                j += 1;
            }
            if j < b.len() && b[j] == b'"' {
                let close: Vec<u8> = std::iter::once(b'"')
                    .chain(std::iter::repeat_n(b'#', hashes))
                    .collect();
                j += 1;
                while j < b.len() && !b[j..].starts_with(&close) {
                    j += 1;
                }
                i = j + close.len();
                out.push_str("\"\"");
            } else {
                out.push('r');
                i += 1;
            }
        } else if b[i] == b'"' {
            i += 1;
            while i < b.len() && b[i] != b'"' {
                i += if b[i] == b'\\' { 2 } else { 1 };
            }
            i += 1;
            out.push_str("\"\"");
        } else if b[i] == b'\'' && i + 2 < b.len() && (b[i + 2] == b'\'' || b[i + 1] == b'\\') {
            // A char literal ('x', '\n', '\''), not a lifetime.
            i += 1;
            while i < b.len() && b[i] != b'\'' {
                i += if b[i] == b'\\' { 2 } else { 1 };
            }
            i += 1;
            out.push_str("' '");
        } else {
            let ch = s[i..].chars().next().unwrap();
            out.push(ch);
            i += ch.len_utf8();
        }
    }
    out
}

fn is_ident(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '_'
}

/// Every path after `prefix::` in `code`, with `{a, b::c}` groups expanded:
/// each as its list of segments.
fn paths_after(code: &str, prefix: &str) -> Vec<Vec<String>> {
    paths_at(code, prefix).into_iter().map(|(_, p)| p).collect()
}

/// [`paths_after`] with the byte offset of each path's prefix.
fn paths_at(code: &str, prefix: &str) -> Vec<(usize, Vec<String>)> {
    let mut out = vec![];
    let pat = format!("{prefix}::");
    let mut from = 0;
    while let Some(k) = code[from..].find(&pat) {
        let at = from + k;
        from = at + pat.len();
        let before = code[..at].chars().next_back();
        if before.is_some_and(|c| is_ident(c) || c == ':') {
            continue;
        }
        let (mut segs, mut found) = (vec![], vec![]);
        expand(&code[from..], &mut segs, &mut found);
        out.extend(found.into_iter().map(|p| (at, p)));
    }
    out
}

/// `code` with every `#[cfg(test)] mod … { … }` blanked: unit tests may
/// build their fixtures from any part of their tool.
fn without_tests(code: &str) -> String {
    let mut out = code.to_string();
    for (_, a, b) in inline_mods(code) {
        let head = code[..a].rfind("#[cfg(test)]");
        if head.is_some_and(|h| !code[h..a].contains(';') && !code[h..a].contains('}')) {
            out.replace_range(a..=b, &" ".repeat(b - a + 1));
        }
    }
    out
}

/// Inline modules (`mod tests { … }`): name and byte span of each.
fn inline_mods(code: &str) -> Vec<(String, usize, usize)> {
    let b = code.as_bytes();
    let mut out = vec![];
    let mut from = 0;
    while let Some(k) = code[from..].find("mod ") {
        let at = from + k;
        from = at + 4;
        if at > 0 && is_ident(code[..at].chars().next_back().unwrap()) {
            continue;
        }
        let rest = &code[from..];
        let name: String = rest.chars().take_while(|c| is_ident(*c)).collect();
        let after = rest[name.len()..].trim_start();
        if name.is_empty() || !after.starts_with('{') {
            continue;
        }
        let open = from + name.len() + (rest[name.len()..].len() - after.len());
        let mut depth = 0;
        let mut end = open;
        for (i, &c) in b.iter().enumerate().skip(open) {
            if c == b'{' {
                depth += 1;
            } else if c == b'}' {
                depth -= 1;
                if depth == 0 {
                    end = i;
                    break;
                }
            }
        }
        out.push((name, open, end));
    }
    out
}

/// Read `a::b::{c, d::e}` at the start of `s` into `out`.
fn expand(s: &str, prefix: &mut Vec<String>, out: &mut Vec<Vec<String>>) -> usize {
    let mut i = 0;
    let b: Vec<char> = s.chars().collect();
    let depth0 = prefix.len();
    loop {
        while i < b.len() && b[i].is_whitespace() {
            i += 1;
        }
        if i < b.len() && b[i] == '{' {
            i += 1;
            loop {
                let rest: String = b[i..].iter().collect();
                let used = expand(&rest, prefix, out);
                i += used;
                while i < b.len() && b[i].is_whitespace() {
                    i += 1;
                }
                if i < b.len() && b[i] == ',' {
                    i += 1;
                    continue;
                }
                if i < b.len() && b[i] == '}' {
                    i += 1;
                }
                break;
            }
            prefix.truncate(depth0);
            return i;
        }
        let start = i;
        while i < b.len() && is_ident(b[i]) {
            i += 1;
        }
        if i == start {
            break;
        }
        prefix.push(b[start..i].iter().collect());
        if b[i..].starts_with(&[':', ':']) {
            i += 2;
            continue;
        }
        break;
    }
    if prefix.len() > depth0 || depth0 > 0 {
        out.push(prefix.clone());
    }
    prefix.truncate(depth0);
    i
}

/// The module path of a file: `src/geom/fft.rs` → [geom, fft];
/// `src/micro/mod.rs` → [micro]; `src/lib.rs` → [].
fn module_of(file: &Path) -> Vec<String> {
    let rel = file.strip_prefix(src()).unwrap();
    let mut segs: Vec<String> = rel
        .iter()
        .map(|s| s.to_string_lossy().into_owned())
        .collect();
    let last = segs.pop().unwrap();
    let stem = last.trim_end_matches(".rs");
    if stem != "mod" && stem != "lib" {
        segs.push(stem.to_string());
    }
    segs
}

/// The file that defines the longest prefix of `path`.
fn file_of(path: &[String], files: &BTreeSet<PathBuf>) -> Option<PathBuf> {
    for n in (0..=path.len()).rev() {
        let base = path[..n].iter().fold(src(), |p, s| p.join(s));
        if n == 0 {
            return Some(src().join("lib.rs"));
        }
        for cand in [base.with_extension("rs"), base.join("mod.rs")] {
            if files.contains(&cand) {
                return Some(cand);
            }
        }
    }
    None
}

fn top(file: &Path) -> String {
    let rel = file.strip_prefix(src()).unwrap();
    let first = rel.iter().next().unwrap().to_string_lossy();
    first.trim_end_matches(".rs").to_string()
}

struct Graph {
    files: BTreeSet<PathBuf>,
    /// file → (file it uses, the path as written)
    edges: BTreeMap<PathBuf, BTreeSet<(PathBuf, String)>>,
}

fn graph() -> Graph {
    let mut list = vec![];
    rust_files(&src(), &mut list);
    let files: BTreeSet<PathBuf> = list.into_iter().collect();
    let mut edges: BTreeMap<PathBuf, BTreeSet<(PathBuf, String)>> = BTreeMap::new();
    for f in &files {
        if f.starts_with(src().join("cli")) || f.starts_with(src().join("bench")) {
            continue; // the binary: its own crate (root src/cli/main.rs)
        }
        let code = without_tests(&code_only(&fs::read_to_string(f).unwrap()));
        let me = module_of(f);
        // mod.rs, lib.rs, or `x.rs` beside its folder `x/`: a module with children.
        let is_mod =
            f.ends_with("mod.rs") || f.ends_with("lib.rs") || f.with_extension("").is_dir();
        let mut targets: Vec<(Vec<String>, String)> = vec![];
        for p in paths_after(&code, "crate") {
            targets.push((p.clone(), format!("crate::{}", p.join("::"))));
        }
        let inline = inline_mods(&code);
        for (at, p) in paths_at(&code, "super") {
            // Inside `mod tests { … }`, `super` is the file's own module.
            let mut here = me.clone();
            for (name, a, b) in &inline {
                if *a < at && at < *b {
                    here.push(name.clone());
                }
            }
            let mut full: Vec<String> = here[..here.len().saturating_sub(1)].to_vec();
            let mut rest = p.as_slice();
            while rest.first().is_some_and(|s| s == "super") {
                full.pop();
                rest = &rest[1..];
            }
            full.extend(rest.iter().cloned());
            targets.push((full, format!("super::{}", p.join("::"))));
        }
        // Paths into the file's own child modules (`cells::Cell` in micro/mod.rs).
        let dir = if f.ends_with("mod.rs") || f.ends_with("lib.rs") {
            f.parent().unwrap().to_path_buf()
        } else {
            f.with_extension("")
        };
        if dir.is_dir() {
            for child in fs::read_dir(&dir).unwrap() {
                let cp = child.unwrap().path();
                let name = cp.file_stem().unwrap().to_string_lossy().into_owned();
                if name == "mod" || cp.join("Cargo.toml").exists() {
                    continue;
                }
                for p in paths_after(&code, &name) {
                    let mut full = me.clone();
                    full.push(name.clone());
                    full.extend(p);
                    targets.push((full, name.clone()));
                }
            }
        }
        for (path, written) in targets {
            let Some(to) = file_of(&path, &files) else {
                continue;
            };
            if &to == f {
                continue;
            }
            // A facade's paths into its own children are not dependencies.
            if is_mod && to.starts_with(&dir) {
                continue;
            }
            edges.entry(f.clone()).or_default().insert((to, written));
        }
    }
    Graph { files, edges }
}

fn rel(p: &Path) -> String {
    p.strip_prefix(src().parent().unwrap())
        .unwrap()
        .display()
        .to_string()
}

#[test]
fn no_module_imports_a_layer_above_it_or_another_tool() {
    let g = graph();
    let mut bad = vec![];
    for (from, tos) in &g.edges {
        let fm = top(from);
        let Some(ok) = allowed(&fm) else { continue };
        for (to, written) in tos {
            let tm = top(to);
            if tm != fm && tm != "lib" && !ok.contains(&tm.as_str()) {
                bad.push(format!("{} uses {} ({written})", rel(from), rel(to)));
            }
        }
    }
    assert!(
        bad.is_empty(),
        "imports that climb a layer (see tests/layers.rs):\n  {}",
        bad.join("\n  ")
    );
}

#[test]
fn no_import_cycles_between_files() {
    let g = graph();
    // Tarjan's strongly connected components, iteratively.
    let ids: Vec<&PathBuf> = g.files.iter().collect();
    let index_of: BTreeMap<&PathBuf, usize> =
        ids.iter().enumerate().map(|(i, p)| (*p, i)).collect();
    let adj: Vec<Vec<usize>> = ids
        .iter()
        .map(|f| {
            g.edges
                .get(*f)
                .map(|s| {
                    s.iter()
                        .filter_map(|(t, _)| index_of.get(t).copied())
                        .collect()
                })
                .unwrap_or_default()
        })
        .collect();
    let n = ids.len();
    let (mut index, mut low, mut on) = (vec![usize::MAX; n], vec![0; n], vec![false; n]);
    let (mut stack, mut next, mut sccs) = (vec![], 0, vec![]);
    for root in 0..n {
        if index[root] != usize::MAX {
            continue;
        }
        let mut work = vec![(root, 0usize)];
        while let Some(&mut (v, ref mut k)) = work.last_mut() {
            if *k == 0 {
                index[v] = next;
                low[v] = next;
                next += 1;
                stack.push(v);
                on[v] = true;
            }
            if *k < adj[v].len() {
                let w = adj[v][*k];
                *k += 1;
                if index[w] == usize::MAX {
                    work.push((w, 0));
                } else if on[w] {
                    low[v] = low[v].min(index[w]);
                }
                continue;
            }
            work.pop();
            if let Some(&(u, _)) = work.last() {
                low[u] = low[u].min(low[v]);
            }
            if low[v] == index[v] {
                let mut comp = vec![];
                loop {
                    let w = stack.pop().unwrap();
                    on[w] = false;
                    comp.push(rel(ids[w]));
                    if w == v {
                        break;
                    }
                }
                if comp.len() > 1 {
                    comp.sort();
                    // Name the imports that close the loop.
                    let mut why = vec![];
                    for a in &comp {
                        for (t, written) in g
                            .edges
                            .get(&src().parent().unwrap().join(a))
                            .into_iter()
                            .flatten()
                        {
                            if comp.contains(&rel(t)) {
                                why.push(format!("      {a} uses {} ({written})", rel(t)));
                            }
                        }
                    }
                    why.dedup();
                    sccs.push(format!("{}\n{}", comp.join(" ↔ "), why.join("\n")));
                }
            }
        }
    }
    assert!(
        sccs.is_empty(),
        "import cycles between files:\n  {}",
        sccs.join("\n  ")
    );
}

#[test]
fn the_reader_sees_real_imports() {
    // The test is only as good as its parser: it must see these.
    let code = code_only(
        "use crate::{core::error::Error, geom::{fft, svg::Svg}};\n// crate::api::x\nlet s = \"crate::pixel\";",
    );
    let paths: Vec<String> = paths_after(&code, "crate")
        .into_iter()
        .map(|p| p.join("::"))
        .collect();
    assert_eq!(paths, ["core::error::Error", "geom::fft", "geom::svg::Svg"]);
    let g = graph();
    let fit = src().join("pattern/fit.rs");
    assert!(
        g.edges[&fit]
            .iter()
            .any(|(t, _)| t.ends_with("core/error.rs")),
        "pattern/fit.rs uses core::error"
    );
}
