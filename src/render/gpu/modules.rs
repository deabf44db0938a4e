//! A small module system for WGSL, which has no includes of its own.
//!
//! A module is a named piece of WGSL. It names the modules it needs on
//! lines of the form `// #import name` (several names may share a line,
//! separated by commas or spaces; by convention they open the file).
//! [`Library::compose`] gives an entry module with everything it imports,
//! directly or not, each module once and after all it imports, so that a
//! pipeline's shader holds only what its entry point uses. The directive is
//! a WGSL comment, so it stays in the composed text harmlessly.
//!
//! Module-scope WGSL declarations may appear in any order, so a module can
//! use a name that another module of the same shader declares without
//! importing it (the shared march calls the `on_sample` its entry file
//! defines; `store_color` writes the `color_out` of the pass's bindings).

use std::borrow::Cow;
use std::collections::{BTreeMap, HashSet};

use thiserror::Error;

const IMPORT: &str = "// #import";

#[derive(Debug, Error, Clone, PartialEq, Eq)]
pub(super) enum ComposeError {
    #[error("WGSL module '{module}' is unknown (imported by {by})")]
    Unknown { module: String, by: String },
    #[error("WGSL modules import each other: {}", .0.join(" -> "))]
    Cycle(Vec<String>),
    #[error("WGSL module '{module}': '{line}' names no module")]
    Malformed { module: String, line: String },
}

/// Named WGSL modules, from which entry modules are composed.
#[derive(Default)]
pub(super) struct Library {
    modules: BTreeMap<String, Cow<'static, str>>,
}

impl Library {
    /// Adds (or replaces) module `name`.
    pub fn add(&mut self, name: impl Into<String>, source: impl Into<Cow<'static, str>>) {
        self.modules.insert(name.into(), source.into());
    }

    /// Module `entry` after everything it imports, in dependency order,
    /// each module once.
    pub fn compose(&self, entry: &str) -> Result<String, ComposeError> {
        let mut out = String::new();
        let mut done = HashSet::new();
        let mut path = Vec::new();
        self.visit(entry, "the pipeline", &mut path, &mut done, &mut out)?;
        Ok(out)
    }

    fn visit<'a>(
        &'a self,
        name: &'a str,
        by: &str,
        path: &mut Vec<&'a str>,
        done: &mut HashSet<&'a str>,
        out: &mut String,
    ) -> Result<(), ComposeError> {
        if done.contains(name) {
            return Ok(());
        }
        if let Some(at) = path.iter().position(|m| *m == name) {
            let mut cycle: Vec<String> = path[at..].iter().map(|m| m.to_string()).collect();
            cycle.push(name.to_string());
            return Err(ComposeError::Cycle(cycle));
        }
        let (name, source) =
            self.modules
                .get_key_value(name)
                .ok_or_else(|| ComposeError::Unknown {
                    module: name.to_string(),
                    by: by.to_string(),
                })?;
        path.push(name);
        for import in imports(name, source)? {
            self.visit(import, &format!("module '{name}'"), path, done, out)?;
        }
        path.pop();
        done.insert(name);
        out.push_str(&format!("// ---- module {name}\n"));
        out.push_str(source);
        if !source.ends_with('\n') {
            out.push('\n');
        }
        Ok(())
    }
}

/// The modules `source` (module `module`) imports, in the order named.
fn imports<'a>(module: &str, source: &'a str) -> Result<Vec<&'a str>, ComposeError> {
    let mut names = Vec::new();
    for line in source.lines() {
        let Some(rest) = line.trim().strip_prefix(IMPORT) else {
            continue;
        };
        let listed: Vec<&str> = rest
            .split(|c: char| c == ',' || c.is_whitespace())
            .filter(|n| !n.is_empty())
            .collect();
        let valid = |n: &&str| n.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
        if listed.is_empty() || !listed.iter().all(valid) || !rest.starts_with(' ') {
            return Err(ComposeError::Malformed {
                module: module.to_string(),
                line: line.trim().to_string(),
            });
        }
        names.extend(listed);
    }
    Ok(names)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn library(modules: &[(&str, &'static str)]) -> Library {
        let mut lib = Library::default();
        for (name, source) in modules {
            lib.add(*name, *source);
        }
        lib
    }

    /// The module names of a composed text, in order.
    fn order(text: &str) -> Vec<&str> {
        text.lines()
            .filter_map(|l| l.strip_prefix("// ---- module "))
            .collect()
    }

    #[test]
    fn imports_come_first_and_once() {
        let lib = library(&[
            ("entry", "// #import march, color\nfn main() {}\n"),
            (
                "march",
                "// #import constants\n// #import bindings\nfn march() {}\n",
            ),
            ("color", "// #import constants\nfn color() {}"),
            ("constants", "const A: u32 = 1u;\n"),
            ("bindings", "// #import constants\n"),
            ("unused", "fn unused() {}\n"),
        ]);
        let text = lib.compose("entry").unwrap();
        assert_eq!(
            order(&text),
            ["constants", "bindings", "march", "color", "entry"]
        );
        assert!(text.contains("fn color() {}\n// ---- module entry"));
        assert!(!text.contains("unused"));
        assert_eq!(lib.compose("constants").unwrap().lines().count(), 2);
    }

    #[test]
    fn an_unknown_import_names_its_importer() {
        let lib = library(&[
            ("entry", "// #import march\n"),
            ("march", "// #import volum\n"),
        ]);
        let err = lib.compose("entry").unwrap_err();
        assert_eq!(
            err,
            ComposeError::Unknown {
                module: "volum".into(),
                by: "module 'march'".into()
            }
        );
        assert_eq!(
            err.to_string(),
            "WGSL module 'volum' is unknown (imported by module 'march')"
        );
        assert!(matches!(
            lib.compose("nothing"),
            Err(ComposeError::Unknown { by, .. }) if by == "the pipeline"
        ));
    }

    #[test]
    fn a_cycle_is_an_error_that_shows_it() {
        let lib = library(&[
            ("entry", "// #import a\n"),
            ("a", "// #import b\n"),
            ("b", "// #import c\n"),
            ("c", "// #import a\n"),
        ]);
        let err = lib.compose("entry").unwrap_err();
        assert_eq!(
            err,
            ComposeError::Cycle(vec!["a".into(), "b".into(), "c".into(), "a".into()])
        );
        assert_eq!(
            err.to_string(),
            "WGSL modules import each other: a -> b -> c -> a"
        );
        let itself = library(&[("a", "// #import a\n")]);
        assert!(matches!(itself.compose("a"), Err(ComposeError::Cycle(c)) if c == ["a", "a"]));
    }

    #[test]
    fn a_directive_without_names_is_refused() {
        for line in [
            "// #import",
            "// #import  ,",
            "// #import a.b",
            "// #importa",
        ] {
            let lib = library(&[("entry", Box::leak(format!("{line}\n").into_boxed_str()))]);
            assert!(
                matches!(lib.compose("entry"), Err(ComposeError::Malformed { .. })),
                "{line}"
            );
        }
    }
}
