//! `cargo xtask cycles`: import cycles between files. File A depends on file B when A names
//! an item of B's module through `use` (re-exports included) or a path in code (`crate::a::f()`,
//! `super::X`, `self::m::Y`, macro arguments too). A path counts toward the deepest module it
//! reaches; `mod x;` is no dependency; an inline module (`mod tests`) belongs to its file.
//! Paths into another crate (`ddastep::..` from the bench) are not followed.

use std::fmt;
use std::path::Path;

use crate::graph::Graph;
use crate::modtree::ModTree;
use crate::paths::{self, Kind, Resolver};
use crate::workspace;

pub struct Report {
    pub crates: usize,
    pub files: usize,
    pub edges: usize,
    /// Each cycle: its files in order (the last depends on the first) and, per step, the
    /// place that makes that file depend on the next.
    pub cycles: Vec<Vec<(String, String)>>,
}

/// Checks every crate root of every workspace member under `root`.
pub fn check_workspace(root: &Path) -> Result<Report, String> {
    let members = workspace::members(root).map_err(|e| format!("{}: {e}", root.join("Cargo.toml").display()))?;
    let roots: Vec<_> = members.iter().flat_map(|m| workspace::crate_roots(m)).collect();
    check_crates(&roots, root)
}

/// Checks the crates whose root files are `roots`; file names in the report are relative to
/// `base`.
pub fn check_crates(roots: &[impl AsRef<Path>], base: &Path) -> Result<Report, String> {
    let mut graph = Graph::default();
    let relative = |path: &Path| {
        let path = path.strip_prefix(base).unwrap_or(path);
        let mut name = path.to_string_lossy().replace('\\', "/");
        while let Some(rest) = name.strip_prefix("../") {
            name = rest.to_owned();
        }
        name
    };
    for root in roots {
        let tree = ModTree::load(root.as_ref())?;
        let references = paths::collect(&tree);
        let resolver = Resolver::new(&tree, &references);
        for file in &tree.files {
            graph.node(&relative(&file.path));
        }
        for r in &references {
            let Some((target, whole)) = resolver.resolve(r.module, &r.segments) else { continue };
            let names_item = match r.kind {
                Kind::Glob => true,
                Kind::Use { .. } | Kind::Code => !whole,
            };
            if !names_item {
                continue;
            }
            let from = graph.node(&relative(&r.file));
            let to = graph.node(&relative(&tree.modules[target].file));
            graph.edge(from, to, || {
                let glob = if matches!(r.kind, Kind::Glob) { "::*" } else { "" };
                format!("{}:{} {}{glob}", relative(&r.file), r.line, r.segments.join("::"))
            });
        }
    }
    let mut cycles = Vec::new();
    for component in graph.components() {
        for cycle in graph.cycles(&component) {
            let steps = (0..cycle.len())
                .map(|i| {
                    let (from, to) = (cycle[i], cycle[(i + 1) % cycle.len()]);
                    (graph.nodes[from].clone(), graph.edges[&(from, to)].clone())
                })
                .collect();
            cycles.push(steps);
        }
    }
    Ok(Report { crates: roots.len(), files: graph.nodes.len(), edges: graph.edges.len(), cycles })
}

impl fmt::Display for Report {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for cycle in &self.cycles {
            let chain: Vec<&str> = cycle.iter().map(|(file, _)| file.as_str()).chain([cycle[0].0.as_str()]).collect();
            writeln!(f, "import cycle: {}", chain.join(" -> "))?;
            for (_, why) in cycle {
                writeln!(f, "    {why}")?;
            }
        }
        let totals = format!("{} crates, {} files, {} dependencies between files", self.crates, self.files, self.edges);
        match self.cycles.len() {
            0 => writeln!(f, "no import cycles ({totals})"),
            n => writeln!(f, "{n} import cycles ({totals})"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs;
    use std::path::PathBuf;

    /// Writes `files` under a fresh temporary folder and returns the folder.
    fn fixture(test: &str, files: &[(&str, &str)]) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("xtask-cycles-{}-{test}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        for (path, text) in files {
            let path = dir.join(path);
            fs::create_dir_all(path.parent().unwrap()).unwrap();
            fs::write(path, text).unwrap();
        }
        dir
    }

    /// The cycles of the crate rooted at `src/lib.rs`, as file chains.
    fn cycles(test: &str, files: &[(&str, &str)]) -> (Vec<Vec<String>>, Report) {
        let dir = fixture(test, files);
        let report = check_crates(&[dir.join("src/lib.rs")], &dir).unwrap();
        fs::remove_dir_all(&dir).unwrap();
        let chains = report.cycles.iter().map(|c| c.iter().map(|(file, _)| file.clone()).collect()).collect();
        (chains, report)
    }

    #[test]
    fn two_files_that_use_each_other() {
        let (found, report) = cycles(
            "two",
            &[
                ("src/lib.rs", "mod a;\nmod b;\n"),
                ("src/a.rs", "use crate::b::B;\npub struct A(B);\n"),
                ("src/b.rs", "pub struct B;\nfn f() -> crate::a::A { todo!() }\n"),
            ],
        );
        assert_eq!(found, vec![vec!["src/a.rs", "src/b.rs"]]);
        let text = report.to_string();
        assert!(text.contains("import cycle: src/a.rs -> src/b.rs -> src/a.rs"), "{text}");
        assert!(text.contains("src/a.rs:1 crate::b::B"), "{text}");
        assert!(text.contains("src/b.rs:2 crate::a::A"), "{text}");
    }

    #[test]
    fn a_chain_of_three_files() {
        let (found, _) = cycles(
            "three",
            &[
                ("src/lib.rs", "mod a;\nmod b;\nmod c;\n"),
                ("src/a.rs", "pub fn f() { crate::b::g() }\n"),
                ("src/b.rs", "pub fn g() { let _: super::c::C; }\n"),
                ("src/c.rs", "use crate::a as alias;\npub struct C;\nfn h() { alias::f() }\n"),
            ],
        );
        assert_eq!(found, vec![vec!["src/a.rs", "src/b.rs", "src/c.rs"]]);
    }

    #[test]
    fn a_child_that_uses_its_parent() {
        let (found, _) = cycles(
            "parent",
            &[
                ("src/lib.rs", "mod emu;\n"),
                ("src/emu/mod.rs", "mod board;\npub use board::Board;\npub const HZ: u32 = 1;\n"),
                ("src/emu/board.rs", "pub struct Board;\nfn hz() -> u32 { super::HZ }\n"),
            ],
        );
        assert_eq!(found, vec![vec!["src/emu/board.rs", "src/emu/mod.rs"]]);
    }

    #[test]
    fn a_glob_import_of_the_parent() {
        let (found, _) = cycles(
            "glob",
            &[
                ("src/lib.rs", "mod la;\n"),
                ("src/la.rs", "mod csv;\npub struct Capture;\npub fn open() { csv::read() }\n"),
                ("src/la/csv.rs", "use super::*;\npub fn read() {}\n"),
            ],
        );
        assert_eq!(found, vec![vec!["src/la.rs", "src/la/csv.rs"]]);
    }

    #[test]
    fn macro_arguments_count() {
        let (found, _) = cycles(
            "macro",
            &[
                ("src/lib.rs", "mod a;\nmod b;\n"),
                ("src/a.rs", "pub const N: u32 = 1;\npub fn f() { println!(\"{}\", crate::b::M); }\n"),
                ("src/b.rs", "pub const M: u32 = 2;\npub fn g() { assert_eq!(super::a::N, 1); }\n"),
            ],
        );
        assert_eq!(found, vec![vec!["src/a.rs", "src/b.rs"]]);
    }

    #[test]
    fn an_inline_test_module_is_part_of_its_file() {
        let (found, report) = cycles(
            "inline",
            &[
                ("src/lib.rs", "mod a;\nmod b;\n"),
                ("src/a.rs", "pub fn f() {}\n#[cfg(test)]\nmod tests {\n    use super::*;\n    #[test]\n    fn t() { f(); super::f(); self::g(); }\n    fn g() {}\n}\n"),
                ("src/b.rs", "use crate::a::f;\npub fn g() { f() }\n"),
            ],
        );
        assert!(found.is_empty(), "{report}");
        assert_eq!(report.edges, 1, "{report}");
    }

    #[test]
    fn a_clean_tree() {
        let (found, report) = cycles(
            "clean",
            &[
                ("src/lib.rs", "pub mod leaf;\npub mod m;\npub use m::top::Top;\n"),
                ("src/leaf.rs", "pub const HZ: u32 = 72_000_000;\n"),
                ("src/m/mod.rs", "pub mod top;\nmod low;\nuse ddastep::motion::engine::Stepper;\n"),
                ("src/m/low.rs", "use crate::leaf::HZ;\npub fn f() -> u32 { HZ }\n"),
                ("src/m/top.rs", "use super::low;\npub struct Top;\nfn g() -> u32 { low::f() + crate::leaf::HZ + ::std::u32::MAX }\n"),
            ],
        );
        assert!(found.is_empty(), "{report}");
        // lib -> top, m/mod.rs -> nothing (`ddastep` is another crate), low -> leaf, top -> low, top -> leaf.
        assert_eq!(report.edges, 4, "{report}");
        assert!(report.to_string().starts_with("no import cycles (1 crates, 5 files, 4 dependencies"), "{report}");
    }

    #[test]
    fn a_reexported_crate_leads_out_of_the_crate() {
        // `crate::la::Analyzer` names the other crate, not lib.rs that re-exports it.
        let (found, report) = cycles(
            "extern",
            &[
                ("src/lib.rs", "pub use ddastep_la as la;\npub mod emu;\npub use emu::Board;\n"),
                ("src/emu.rs", "pub struct Board;\nfn f() -> crate::la::Analyzer { todo!() }\n"),
            ],
        );
        assert!(found.is_empty(), "{report}");
        assert_eq!(report.edges, 1, "{report}");
    }

    #[test]
    fn a_path_counts_toward_the_deepest_module() {
        // `crate::m::low::f` names low.rs, not m/mod.rs, so the child does not depend on its parent.
        let (found, report) = cycles(
            "deepest",
            &[
                ("src/lib.rs", "mod m;\n"),
                ("src/m/mod.rs", "mod low;\nmod top;\npub use top::Top;\n"),
                ("src/m/low.rs", "pub fn f() {}\n"),
                ("src/m/top.rs", "pub struct Top;\nfn g() { crate::m::low::f() }\n"),
            ],
        );
        assert!(found.is_empty(), "{report}");
    }
}
