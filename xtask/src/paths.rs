//! The paths a file names (`use` trees, paths in code and in macro arguments) and their
//! resolution to the deepest module of the crate that they reach. Used by `cycles.rs`.

use std::collections::{BTreeMap, BTreeSet};
use std::path::PathBuf;

use proc_macro2::{Spacing, TokenStream, TokenTree};
use syn::visit::{self, Visit};

use crate::modtree::{ModId, ModTree, ROOT};

pub enum Kind {
    /// `use a::b;` or `use a::b as name;` (`name` is `None` for `as _`).
    Use { name: Option<String> },
    /// `use a::b::*;`
    Glob,
    /// A path in code, a type or a macro argument: `a::b::f()`.
    Code,
}

/// One path named in a file, relative to the module it is written in.
pub struct Reference {
    pub file: PathBuf,
    pub line: usize,
    pub module: ModId,
    pub segments: Vec<String>,
    pub kind: Kind,
}

/// Every path that the crate's files name, except those with a leading `::` (other crates).
pub fn collect(tree: &ModTree) -> Vec<Reference> {
    let mut collector = Collector { tree, file: PathBuf::new(), stack: Vec::new(), out: Vec::new() };
    for source in &tree.files {
        collector.file.clone_from(&source.path);
        collector.stack = vec![source.module];
        collector.visit_file(&source.ast);
    }
    collector.out
}

struct Collector<'t> {
    tree: &'t ModTree,
    file: PathBuf,
    stack: Vec<ModId>,
    out: Vec<Reference>,
}

impl Collector<'_> {
    fn module(&self) -> ModId {
        *self.stack.last().expect("a module")
    }

    fn push(&mut self, segments: Vec<String>, kind: Kind, line: usize) {
        self.out.push(Reference { file: self.file.clone(), line, module: self.module(), segments, kind });
    }

    fn use_tree(&mut self, tree: &syn::UseTree, prefix: &mut Vec<String>) {
        match tree {
            syn::UseTree::Path(p) => {
                prefix.push(name(&p.ident));
                self.use_tree(&p.tree, prefix);
                prefix.pop();
            }
            syn::UseTree::Name(n) if n.ident == "self" => {
                let alias = prefix.last().cloned();
                self.push(prefix.clone(), Kind::Use { name: alias }, n.ident.span().start().line);
            }
            syn::UseTree::Name(n) => {
                let mut segments = prefix.clone();
                segments.push(name(&n.ident));
                self.push(segments, Kind::Use { name: Some(name(&n.ident)) }, n.ident.span().start().line);
            }
            syn::UseTree::Rename(r) => {
                let mut segments = prefix.clone();
                if r.ident != "self" {
                    segments.push(name(&r.ident));
                }
                let alias = (r.rename != "_").then(|| name(&r.rename));
                self.push(segments, Kind::Use { name: alias }, r.ident.span().start().line);
            }
            syn::UseTree::Glob(g) => self.push(prefix.clone(), Kind::Glob, g.star_token.spans[0].start().line),
            syn::UseTree::Group(g) => {
                for item in &g.items {
                    self.use_tree(item, prefix);
                }
            }
        }
    }

    /// Paths such as `crate::a::B` inside macro arguments, which syn leaves as tokens.
    fn scan_tokens(&mut self, tokens: TokenStream) {
        let tokens: Vec<TokenTree> = tokens.into_iter().collect();
        let mut i = 0;
        while i < tokens.len() {
            let TokenTree::Ident(first) = &tokens[i] else {
                if let TokenTree::Group(group) = &tokens[i] {
                    self.scan_tokens(group.stream());
                }
                i += 1;
                continue;
            };
            let continues_path = i > 0 && matches!(&tokens[i - 1], TokenTree::Punct(p) if p.as_char() == ':' || p.as_char() == '$');
            let mut segments = vec![name(first)];
            let mut next = i + 1;
            while let (Some(TokenTree::Punct(a)), Some(TokenTree::Punct(b)), Some(TokenTree::Ident(ident))) =
                (tokens.get(next), tokens.get(next + 1), tokens.get(next + 2))
            {
                if a.as_char() != ':' || a.spacing() != Spacing::Joint || b.as_char() != ':' {
                    break;
                }
                segments.push(name(ident));
                next += 3;
            }
            if !continues_path && segments.len() > 1 {
                self.push(segments, Kind::Code, first.span().start().line);
            }
            i = next;
        }
    }
}

impl<'ast> Visit<'ast> for Collector<'_> {
    fn visit_item_mod(&mut self, item: &'ast syn::ItemMod) {
        let Some((_, items)) = &item.content else { return };
        let here = self.module();
        let inner = self.tree.modules[here].children.get(&name(&item.ident)).copied().unwrap_or(here);
        self.stack.push(inner);
        for item in items {
            self.visit_item(item);
        }
        self.stack.pop();
    }

    fn visit_item_use(&mut self, item: &'ast syn::ItemUse) {
        if item.leading_colon.is_none() {
            self.use_tree(&item.tree, &mut Vec::new());
        }
    }

    fn visit_path(&mut self, path: &'ast syn::Path) {
        if path.leading_colon.is_none() {
            if let Some(first) = path.segments.first() {
                let segments = path.segments.iter().map(|s| name(&s.ident)).collect();
                self.push(segments, Kind::Code, first.ident.span().start().line);
            }
        }
        for segment in &path.segments {
            visit::visit_path_arguments(self, &segment.arguments);
        }
    }

    fn visit_macro(&mut self, mac: &'ast syn::Macro) {
        self.scan_tokens(mac.tokens.clone());
    }

    // `#[derive(..)]`, `#[cfg(..)]`, doc strings: no paths into the crate.
    fn visit_attribute(&mut self, _: &'ast syn::Attribute) {}
}

fn name(ident: &proc_macro2::Ident) -> String {
    let text = ident.to_string();
    text.strip_prefix("r#").map(str::to_owned).unwrap_or(text)
}

/// Resolves paths against the module tree and the module names that `use` brings into scope.
pub struct Resolver<'t> {
    tree: &'t ModTree,
    /// Per module: names that `use` binds to a module (`use super::board;`).
    aliases: Vec<BTreeMap<String, ModId>>,
    /// Per module: modules whose names a glob brings in (`use super::*;`).
    globs: Vec<Vec<ModId>>,
    /// Per module: names that `use` binds to another crate (`pub use ddastep_la as la;`), so
    /// that `crate::la::X` leads out of the crate, not to the file that re-exports it.
    externs: Vec<BTreeSet<String>>,
}

impl<'t> Resolver<'t> {
    pub fn new(tree: &'t ModTree, references: &[Reference]) -> Resolver<'t> {
        let n = tree.modules.len();
        let mut resolver = Resolver { tree, aliases: vec![BTreeMap::new(); n], globs: vec![Vec::new(); n], externs: vec![BTreeSet::new(); n] };
        // A `use` may name a module through another `use`: repeat until nothing new binds.
        loop {
            let mut changed = false;
            for r in references {
                let Some((target, true)) = resolver.resolve(r.module, &r.segments) else { continue };
                match &r.kind {
                    Kind::Use { name: Some(name) } if !resolver.aliases[r.module].contains_key(name) => {
                        resolver.aliases[r.module].insert(name.clone(), target);
                        changed = true;
                    }
                    Kind::Glob if !resolver.globs[r.module].contains(&target) => {
                        resolver.globs[r.module].push(target);
                        changed = true;
                    }
                    _ => {}
                }
            }
            if !changed {
                break;
            }
        }
        for r in references {
            let relative = r.segments.first().is_some_and(|s| !matches!(s.as_str(), "crate" | "self" | "super" | "Self"));
            if let (Kind::Use { name: Some(name) }, true, None) = (&r.kind, relative, resolver.resolve(r.module, &r.segments)) {
                resolver.externs[r.module].insert(name.clone());
            }
        }
        resolver
    }

    /// The deepest module that `segments`, written in `module`, reach, and whether they name
    /// that module itself (rather than an item in it). `None`: another crate, or a local item.
    pub fn resolve(&self, module: ModId, segments: &[String]) -> Option<(ModId, bool)> {
        let modules = &self.tree.modules;
        let mut at = match segments.first()?.as_str() {
            "crate" => ROOT,
            "self" => module,
            "super" => modules[module].parent?,
            "Self" => return None,
            first => self.lookup(module, first)?,
        };
        let mut i = 1;
        while i < segments.len() && segments[i] == "super" {
            at = modules[at].parent?;
            i += 1;
        }
        while let Some(segment) = segments.get(i) {
            match modules[at].children.get(segment) {
                Some(&child) => at = child,
                None if i > 0 && self.externs[at].contains(segment) => return None,
                None => break,
            }
            i += 1;
        }
        Some((at, i == segments.len()))
    }

    /// A module named `name` in the scope of `module`: a child, a `use`d module, or a child
    /// of a glob-imported module.
    fn lookup(&self, module: ModId, name: &str) -> Option<ModId> {
        let modules = &self.tree.modules;
        modules[module]
            .children
            .get(name)
            .or_else(|| self.aliases[module].get(name))
            .or_else(|| self.globs[module].iter().find_map(|&g| modules[g].children.get(name).or_else(|| self.aliases[g].get(name))))
            .copied()
    }
}
