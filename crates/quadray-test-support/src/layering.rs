//! The layering check of quadray's crates: every path a source file names with `crate::` or
//! `super::` (in `use` lines and in code, not in comments) must lead to a module of its own layer
//! or one below. Each crate's `tests/layers.rs` lists its layers and calls [`assert_layered`].

use std::collections::BTreeMap;
use std::path::Path;

/// The module a source file is, as a path under the crate root ("" for lib.rs).
fn module_of(src: &Path, file: &Path) -> String {
    let relative = file.strip_prefix(src).unwrap().with_extension("");
    let mut parts: Vec<String> = relative
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    let root = parts.len() == 1 && parts[0] == "main";
    if root || matches!(parts.last().map(String::as_str), Some("mod" | "lib")) {
        parts.pop();
    }
    parts.join("::")
}

/// Every `.rs` file under `dir`, appended to `out`.
pub fn rust_files(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The code of a line without its `//` comment (no string in quadray's crates holds `//` before a
/// path).
fn code(line: &str) -> &str {
    line.find("//").map_or(line, |i| &line[..i])
}

/// Every module path a file names: `crate::a::b` and `super::a::b`, each item of a `{...}`
/// group after one, resolved against the file's module (`super` inside an inline `mod tests`
/// is the file itself).
fn named_paths(module: &str, text: &str) -> Vec<(usize, String)> {
    let own: Vec<&str> = module.split("::").filter(|s| !s.is_empty()).collect();
    let parent = |inline_test: bool| -> Vec<&str> {
        if inline_test {
            own.clone()
        } else {
            own[..own.len().saturating_sub(1)].to_vec()
        }
    };
    let mut paths = Vec::new();
    let mut inline_test = false;
    let mut joined = String::new();
    let mut line_of = Vec::new();
    for (n, line) in text.lines().enumerate() {
        if line.starts_with("mod tests {") {
            inline_test = true;
        } else if line == "}" {
            inline_test = false;
        }
        let code = code(line);
        joined.push_str(code);
        joined.push('\n');
        line_of.extend(std::iter::repeat_n((n + 1, inline_test), code.len() + 1));
    }
    let bytes = joined.as_bytes();
    for start in 0..bytes.len() {
        let rest = &joined[start..];
        let (root, after) = if rest.starts_with("crate::") {
            (Vec::new(), "crate::".len())
        } else if rest.starts_with("super::") {
            // each further `super::` goes one module up
            let ups = (0..)
                .take_while(|i| rest[i * "super::".len()..].starts_with("super::"))
                .count();
            let mut root = parent(line_of[start].1);
            root.truncate(root.len().saturating_sub(ups - 1));
            (root, ups * "super::".len())
        } else {
            continue;
        };
        if start > 0 && (bytes[start - 1].is_ascii_alphanumeric() || bytes[start - 1] == b'_') {
            continue;
        }
        if start > 1 && &joined[start - 2..start] == "::" {
            continue;
        }
        let line = line_of[start].0;
        let tail = &joined[start + after..];
        for item in items(tail) {
            let mut path = root.iter().map(|s| s.to_string()).collect::<Vec<_>>();
            path.extend(item.split("::").map(str::to_string));
            paths.push((line, path.join("::")));
        }
    }
    paths
}

/// The paths after `crate::` or `super::`: one path, or each item of a `{...}` group after one
/// (its items' own groups cut to their first segment).
fn items(tail: &str) -> Vec<String> {
    let run: String = tail
        .chars()
        .take_while(|c| c.is_ascii_alphanumeric() || *c == '_' || *c == ':')
        .collect();
    let rest = &tail[run.len()..];
    let Some(group) = rest
        .strip_prefix('{')
        .filter(|_| run.is_empty() || run.ends_with("::"))
    else {
        return vec![run.trim_end_matches(':').to_string()];
    };
    let mut depth = 0;
    let mut item = String::new();
    let mut out = Vec::new();
    for c in group.chars() {
        match c {
            '{' => depth += 1,
            '}' if depth == 0 => break,
            '}' => depth -= 1,
            ',' if depth == 0 => out.push(std::mem::take(&mut item)),
            _ if depth == 0 => item.push(c),
            _ => {}
        }
    }
    out.push(item);
    out.iter()
        .flat_map(|i| items(i.trim()))
        .filter(|i| !i.is_empty())
        .map(|i| format!("{run}{i}"))
        .collect()
}

/// What the `facades` (module, file) re-export: `facade::Name` -> the path it names.
fn re_exports(src: &Path, facades: &[(&str, &str)]) -> BTreeMap<String, String> {
    let mut map = BTreeMap::new();
    for &(facade, file) in facades {
        let text = std::fs::read_to_string(src.join(file)).unwrap();
        let own: Vec<&str> = facade.split("::").filter(|s| !s.is_empty()).collect();
        let code: String = text
            .lines()
            .map(|l| code(l).replace("pub(crate) use ", "pub use ") + "\n")
            .collect();
        for statement in code.split("pub use ").skip(1) {
            let statement = &statement[..statement.find(';').unwrap()];
            let (root, tail) = if let Some(t) = statement.strip_prefix("crate::") {
                (Vec::new(), t)
            } else if let Some(t) = statement.strip_prefix("super::") {
                (own[..own.len() - 1].to_vec(), t)
            } else {
                (own.clone(), statement)
            };
            let (prefix, group) = match tail.find('{') {
                Some(i) => (&tail[..i], &tail[i..]),
                None => ("", tail),
            };
            for item in items(group) {
                let mut path: Vec<String> = root.iter().map(|s| s.to_string()).collect();
                path.extend(
                    prefix
                        .split("::")
                        .chain(item.split("::"))
                        .filter(|s| !s.is_empty())
                        .map(str::to_string),
                );
                let name = path.last().unwrap().clone();
                let exported = own
                    .iter()
                    .map(|s| s.to_string())
                    .chain([name])
                    .collect::<Vec<_>>();
                map.insert(exported.join("::"), path.join("::"));
            }
        }
    }
    map
}

/// The layer of the module `path` leads to: through the facades' re-exports to the module that
/// defines the item, then the longest known module it starts with.
fn layer_of(
    layer: &BTreeMap<&str, usize>,
    re_exports: &BTreeMap<String, String>,
    path: &str,
) -> usize {
    let mut path = path.to_string();
    for _ in 0..4 {
        let mut resolved = None;
        for (exported, target) in re_exports {
            if path == *exported || path.starts_with(&format!("{exported}::")) {
                resolved = Some(format!("{target}{}", &path[exported.len()..]));
            }
        }
        match resolved {
            Some(p) if p != path => path = p,
            _ => break,
        }
    }
    let mut target = path.as_str();
    loop {
        if let Some(&l) = layer.get(target) {
            return l;
        }
        match target.rfind("::") {
            Some(i) => target = &target[..i],
            None if !target.is_empty() => target = "",
            None => return usize::MAX,
        }
    }
}

/// Checks every source file under `src` against `layers` (modules by layer, bottom first),
/// resolving names through the `facades` (module, file) that re-export the layers below them;
/// prints and returns the imports that go upward.
pub fn upward_imports(src: &Path, layers: &[&[&str]], facades: &[(&str, &str)]) -> Vec<String> {
    let layer: BTreeMap<&str, usize> = layers
        .iter()
        .enumerate()
        .flat_map(|(i, modules)| modules.iter().map(move |m| (*m, i)))
        .collect();
    let re_exports = re_exports(src, facades);
    let mut files = Vec::new();
    rust_files(src, &mut files);
    files.sort();
    let mut wrong = Vec::new();
    for file in &files {
        let module = module_of(src, file);
        let Some(&own) = layer.get(module.as_str()) else {
            wrong.push(format!("{module}: not in LAYERS"));
            continue;
        };
        let text = std::fs::read_to_string(file).unwrap();
        for (line, path) in named_paths(&module, &text) {
            let found = layer_of(&layer, &re_exports, &path);
            if found > own {
                wrong.push(format!(
                    "{}:{line}: {module} (layer {own}) names {path} (layer {found})",
                    file.strip_prefix(src).unwrap().display()
                ));
            }
        }
    }
    for w in &wrong {
        println!("{w}");
    }
    println!(
        "{} files checked, {} imports upward",
        files.len(),
        wrong.len()
    );
    wrong
}

/// Fails naming every upward import of the crate at `manifest_dir` ([`upward_imports`] over its
/// `src/`).
pub fn assert_layered(manifest_dir: &str, layers: &[&[&str]], facades: &[(&str, &str)]) {
    let wrong = upward_imports(&Path::new(manifest_dir).join("src"), layers, facades);
    assert!(wrong.is_empty(), "{wrong:#?}");
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A crate `src/` of three modules, each written from `files` (path, text), in a fresh folder.
    fn source_tree(test: &str, files: &[(&str, &str)]) -> std::path::PathBuf {
        let src = std::env::temp_dir()
            .join(format!("quadray-layering-{}-{test}", std::process::id()))
            .join("src");
        let _ = std::fs::remove_dir_all(&src);
        for (path, text) in files {
            let file = src.join(path);
            std::fs::create_dir_all(file.parent().unwrap()).unwrap();
            std::fs::write(file, text).unwrap();
        }
        src
    }

    const LAYERS: &[&[&str]] = &[&["low"], &["high", "high::inner"], &[""]];

    /// An import of a higher layer is found, through a `use` group, `super::` and a facade's
    /// re-export; imports downward and comments are not.
    #[test]
    fn upward_imports_are_named_and_downward_ones_pass() {
        let src = source_tree(
            "both",
            &[
                (
                    "lib.rs",
                    "pub mod high;\npub mod low;\npub use high::Top;\n",
                ),
                ("high/mod.rs", "pub mod inner;\nuse crate::low::Base;\n"),
                (
                    "high/inner.rs",
                    "use super::super::low::Base;\n// crate::Top\n",
                ),
                (
                    "low.rs",
                    "use crate::{high::inner::X, Top};\nfn f() { super::high::g() }\n",
                ),
            ],
        );
        let wrong = upward_imports(&src, LAYERS, &[("", "lib.rs")]);
        assert_eq!(wrong.len(), 3, "{wrong:#?}");
        assert!(wrong.iter().all(|w| w.starts_with("low.rs:")), "{wrong:#?}");
        assert!(wrong.iter().any(|w| w.ends_with("names Top (layer 1)")));
    }

    /// A file whose module has no layer is an error of its own.
    #[test]
    fn a_module_without_a_layer_is_named() {
        let src = source_tree("unlisted", &[("lib.rs", ""), ("stray.rs", "")]);
        assert_eq!(
            upward_imports(&src, LAYERS, &[]),
            vec!["stray: not in LAYERS".to_string()]
        );
    }
}
