//! The layers the code says it has, checked against the code.
//!
//! Each checked module states its layers once, in its module documentation,
//! as a line `Layers: a → b, c → d` (top to bottom; modules separated by
//! commas share a layer). This test reads that line and every `crate::X`
//! and `super::X` path of the module's files (comments and `#[cfg(test)]
//! mod tests` left out) and fails on an edge that runs upward or sideways:
//! a module may use only modules of layers below its own. A module the
//! line does not name is an error too, so a new file must take its place.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Where a module's children are and how their files name each other.
struct Scope {
    /// Folder of the module's files.
    dir: &'static str,
    /// The file whose documentation states the layers.
    doc: &'static str,
    /// `true`: the children are the crate's top-level modules (`crate::X`);
    /// `false`: files of one folder (`super::X`, or `crate::<path>::X`).
    top_level: bool,
    /// The module's path from the crate root (`od`), for `crate::od::X`.
    path: &'static str,
    /// Test-only files (not checked).
    test_only: &'static [&'static str],
}

const SCOPES: &[Scope] = &[
    Scope {
        dir: "slave/src",
        doc: "lib.rs",
        top_level: true,
        path: "",
        test_only: &["testing"],
    },
    Scope {
        dir: "sim/src",
        doc: "lib.rs",
        top_level: true,
        path: "",
        test_only: &["testing"],
    },
    Scope {
        dir: "profiles/cia402/src",
        doc: "lib.rs",
        top_level: true,
        path: "",
        test_only: &[],
    },
    Scope {
        dir: "slave/src/od",
        doc: "mod.rs",
        top_level: false,
        path: "od",
        test_only: &[],
    },
    Scope {
        dir: "devices/hcs-dma22/src",
        doc: "lib.rs",
        top_level: true,
        path: "",
        test_only: &[],
    },
    Scope {
        dir: "devices/hcs-dma22/src/description",
        doc: "mod.rs",
        top_level: false,
        path: "description",
        test_only: &[],
    },
    Scope {
        dir: "devices/hcs-dma22/src/app",
        doc: "mod.rs",
        top_level: false,
        path: "app",
        test_only: &["tests"],
    },
    Scope {
        dir: "devices/pam-199-p-etc/src",
        doc: "lib.rs",
        top_level: true,
        path: "",
        test_only: &["tests"],
    },
    Scope {
        dir: "examples/io8/src",
        doc: "lib.rs",
        top_level: true,
        path: "",
        test_only: &["tests"],
    },
    Scope {
        dir: "devices/hcs-dma22/src/telegram",
        doc: "mod.rs",
        top_level: false,
        path: "telegram",
        test_only: &["props", "seed_vectors"],
    },
];

fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The layers of the `Layers:` line of `doc` (a module's documentation):
/// module name → layer number, 0 the top. `None` without such a line.
fn layers_of(doc: &str) -> Option<BTreeMap<String, usize>> {
    let mut text = String::new();
    let mut on = false;
    for line in doc.lines() {
        let Some(l) = line.trim_start().strip_prefix("//!") else {
            continue;
        };
        let l = l.trim();
        if let Some(rest) = l.strip_prefix("Layers:") {
            on = true;
            text.push_str(rest);
        } else if on {
            if l.is_empty() {
                break;
            }
            text.push(' ');
            text.push_str(l);
        }
    }
    if !on {
        return None;
    }
    let mut map = BTreeMap::new();
    for (n, layer) in text.split('→').enumerate() {
        for m in layer.split(',') {
            let m = m.trim().trim_matches('`').trim();
            if !m.is_empty() {
                map.insert(m.to_string(), n);
            }
        }
    }
    Some(map)
}

/// The code of `source` without comments and without its test module.
fn code_of(source: &str) -> String {
    let cut = source
        .find("#[cfg(test)]\nmod tests")
        .or_else(|| source.find("#[cfg(test)]\n#[allow("))
        .unwrap_or(source.len());
    source[..cut]
        .lines()
        .filter(|l| !l.trim_start().starts_with("//"))
        .collect::<Vec<_>>()
        .join("\n")
}

/// The names a path prefix reaches in `code`: `prefix::x` and the first
/// segment of every item of `prefix::{x, y::z}`.
fn reached(code: &str, prefix: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = code;
    while let Some(at) = rest.find(prefix) {
        let before = rest[..at].chars().last();
        rest = &rest[at + prefix.len()..];
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
                out.push(name);
            }
        } else {
            let name: String = rest
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            out.push(name);
        }
    }
    out
}

/// Upward or sideways edges of the modules `sources` (name, code) under
/// `layers`, and modules the layers do not name.
fn violations(
    layers: &BTreeMap<String, usize>,
    sources: &[(String, String)],
    prefixes: &[String],
) -> Vec<String> {
    let mut out = Vec::new();
    for (module, source) in sources {
        let Some(&own) = layers.get(module) else {
            out.push(format!("module `{module}` is in no layer"));
            continue;
        };
        let code = code_of(source);
        let mut seen = std::collections::BTreeSet::new();
        for prefix in prefixes {
            for target in reached(&code, prefix) {
                if target == *module || !seen.insert(target.clone()) {
                    continue;
                }
                if let Some(&theirs) = layers.get(&target)
                    && theirs <= own
                {
                    out.push(format!(
                        "`{module}` (layer {own}) uses `{target}` (layer {theirs}): \
                         a module may use only layers below its own"
                    ));
                }
            }
        }
    }
    out
}

/// The modules of a scope with their code (a folder module's files joined).
fn sources(scope: &Scope) -> Vec<(String, String)> {
    let dir = workspace().join(scope.dir);
    let mut map: BTreeMap<String, String> = BTreeMap::new();
    let mut files = Vec::new();
    let mut stack = vec![dir.clone()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap_or_else(|e| panic!("{}: {e}", d.display())) {
            let p = e.expect("entry").path();
            if p.is_dir() {
                if scope.top_level {
                    stack.push(p);
                }
            } else if p.extension().is_some_and(|x| x == "rs") {
                files.push(p);
            }
        }
    }
    for p in files {
        let rel = p.strip_prefix(&dir).expect("inside");
        let first = rel.components().next().expect("a component");
        let name = first
            .as_os_str()
            .to_string_lossy()
            .trim_end_matches(".rs")
            .to_string();
        if name == scope.doc.trim_end_matches(".rs") || name == "mod" {
            continue;
        }
        if scope.test_only.contains(&name.as_str()) {
            continue;
        }
        let text = std::fs::read_to_string(&p).expect("source");
        // Each file cut at its own test module: a folder module's files
        // joined first would hide everything after the first one's tests.
        let code = code_of(&text);
        let joined = map.entry(name).or_default();
        joined.push_str(&code);
        joined.push('\n');
    }
    map.into_iter().collect()
}

#[test]
fn every_module_uses_only_the_layers_below_its_own() {
    let mut all = Vec::new();
    for scope in SCOPES {
        let doc_path = workspace().join(scope.dir).join(scope.doc);
        let doc = std::fs::read_to_string(&doc_path).expect("module documentation");
        let layers =
            layers_of(&doc).unwrap_or_else(|| panic!("{}: no `Layers:` line", doc_path.display()));
        let prefixes = if scope.top_level {
            vec!["crate::".to_string()]
        } else {
            vec!["super::".to_string(), format!("crate::{}::", scope.path)]
        };
        let found = sources(scope);
        assert!(found.len() >= 2, "{}: {} modules", scope.dir, found.len());
        for v in violations(&layers, &found, &prefixes) {
            all.push(format!("{}: {v}", scope.dir));
        }
    }
    assert!(all.is_empty(), "layer violations:\n{}", all.join("\n"));
}

#[test]
fn a_planted_upward_edge_is_reported() {
    let layers = layers_of("//! Layers: `top` → `mid`, `side` → `leaf`\n//!\n").expect("layers");
    let clean = vec![
        (
            "top".to_string(),
            "use crate::mid::X;\nuse crate::leaf::Y;".to_string(),
        ),
        ("mid".to_string(), "fn f() { crate::leaf::g() }".to_string()),
        ("side".to_string(), "use crate::{leaf, wire};".to_string()),
        (
            "leaf".to_string(),
            "// crate::top in a comment is no use\n".to_string(),
        ),
    ];
    let p = ["crate::".to_string()];
    assert!(violations(&layers, &clean, &p).is_empty());
    // The leaf reaching up, a group import reaching sideways, a new
    // module outside the list.
    let mut planted = clean.clone();
    planted[3].1.push_str("use crate::mid::Thing;\n");
    planted[2].1 = "use crate::{leaf, mid::Other};".to_string();
    planted.push(("stray".to_string(), String::new()));
    let v = violations(&layers, &planted, &p);
    assert_eq!(v.len(), 3, "{v:#?}");
    for want in [
        "`leaf` (layer 2) uses `mid` (layer 1)",
        "`side` (layer 1) uses `mid` (layer 1)",
        "`stray` is in no layer",
    ] {
        assert!(v.iter().any(|x| x.contains(want)), "{want}: {v:#?}");
    }
    // Test modules do not count.
    let tests = vec![(
        "leaf".to_string(),
        "fn f() {}\n#[cfg(test)]\nmod tests {\n use crate::top::T;\n}\n".to_string(),
    )];
    assert!(violations(&layers, &tests, &p).is_empty());
}

#[test]
fn an_upward_edge_after_another_files_test_module_is_reported() {
    // A folder module of two files: the first ends in a test module, the
    // second uses a layer above its own.
    let dir = std::env::temp_dir().join(format!("layers-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("leaf")).expect("temp dir");
    std::fs::write(dir.join("lib.rs"), "//! Layers: `top` → `leaf`\n//!\n").expect("lib.rs");
    std::fs::write(dir.join("top.rs"), "use crate::leaf::Y;\n").expect("top.rs");
    std::fs::write(
        dir.join("leaf/a.rs"),
        "pub struct Y;\n#[cfg(test)]\nmod tests {\n    use super::*;\n}\n",
    )
    .expect("a.rs");
    std::fs::write(dir.join("leaf/b.rs"), "use crate::top::X;\n").expect("b.rs");
    let scope = Scope {
        dir: Box::leak(dir.to_string_lossy().into_owned().into_boxed_str()),
        doc: "lib.rs",
        top_level: true,
        path: "",
        test_only: &[],
    };
    let layers =
        layers_of(&std::fs::read_to_string(dir.join("lib.rs")).expect("lib.rs")).expect("layers");
    let v = violations(&layers, &sources(&scope), &["crate::".to_string()]);
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(v.len(), 1, "{v:#?}");
    assert!(
        v[0].contains("`leaf` (layer 1) uses `top` (layer 0)"),
        "{v:#?}"
    );
}
