//! The module tree of one crate: which file each module lives in, read from the `mod`
//! declarations starting at the crate root (every `#[cfg]` branch counts). Used by `paths.rs`
//! to resolve paths and by `cycles.rs`.

use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};

/// Index of a module in [`ModTree::modules`].
pub type ModId = usize;

pub struct Module {
    /// The file that holds the module's items (an inline module shares its parent's file).
    pub file: PathBuf,
    pub parent: Option<ModId>,
    pub children: BTreeMap<String, ModId>,
    /// Where the files of `mod x;` declared inside this module live.
    dir: PathBuf,
}

/// A parsed source file and the module its top-level items belong to.
pub struct SourceFile {
    pub path: PathBuf,
    pub module: ModId,
    pub ast: syn::File,
}

pub struct ModTree {
    pub modules: Vec<Module>,
    pub files: Vec<SourceFile>,
}

pub const ROOT: ModId = 0;

impl ModTree {
    /// Reads the crate whose root file is `root_file`, and every file it declares with `mod`.
    pub fn load(root_file: &Path) -> Result<ModTree, String> {
        let dir = root_file.parent().unwrap_or(Path::new(".")).to_path_buf();
        let mut tree = ModTree { modules: Vec::new(), files: Vec::new() };
        tree.modules.push(Module { file: root_file.to_path_buf(), parent: None, children: BTreeMap::new(), dir });
        tree.load_file(root_file, ROOT)?;
        Ok(tree)
    }

    fn load_file(&mut self, path: &Path, module: ModId) -> Result<(), String> {
        let text = fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let ast = syn::parse_file(&text).map_err(|e| {
            let at = e.span().start();
            format!("{}:{}:{}: {e}", path.display(), at.line, at.column + 1)
        })?;
        self.add_items(&ast.items, module, path)?;
        self.files.push(SourceFile { path: path.to_path_buf(), module, ast });
        Ok(())
    }

    fn add_items(&mut self, items: &[syn::Item], module: ModId, file: &Path) -> Result<(), String> {
        for item in items {
            let syn::Item::Mod(decl) = item else { continue };
            let name = decl.ident.to_string();
            let parent_dir = self.modules[module].dir.clone();
            let child = self.modules.len();
            match &decl.content {
                Some((_, inner)) => {
                    self.push_child(module, &name, file.to_path_buf(), parent_dir.join(&name));
                    self.add_items(inner, child, file)?;
                }
                None => {
                    let file_dir = file.parent().unwrap_or(Path::new("."));
                    let Some(child_file) = declared_file(decl, &parent_dir, file_dir, &name) else {
                        return Err(format!("{}: no file for `mod {name};`", file.display()));
                    };
                    let child_dir = if child_file.file_name().is_some_and(|f| f == "mod.rs") || path_attr(decl).is_some() {
                        child_file.parent().unwrap_or(Path::new(".")).to_path_buf()
                    } else {
                        parent_dir.join(&name)
                    };
                    self.push_child(module, &name, child_file.clone(), child_dir);
                    self.load_file(&child_file, child)?;
                }
            }
        }
        Ok(())
    }

    fn push_child(&mut self, parent: ModId, name: &str, file: PathBuf, dir: PathBuf) {
        let id = self.modules.len();
        self.modules.push(Module { file, parent: Some(parent), children: BTreeMap::new(), dir });
        self.modules[parent].children.insert(name.to_owned(), id);
    }
}

/// `dir/name.rs`, `dir/name/mod.rs`, or `#[path]` relative to the declaring file's folder.
fn declared_file(decl: &syn::ItemMod, dir: &Path, file_dir: &Path, name: &str) -> Option<PathBuf> {
    if let Some(path) = path_attr(decl) {
        return Some(file_dir.join(path));
    }
    [dir.join(format!("{name}.rs")), dir.join(name).join("mod.rs")].into_iter().find(|f| f.is_file())
}

fn path_attr(decl: &syn::ItemMod) -> Option<String> {
    decl.attrs.iter().find_map(|attr| match &attr.meta {
        syn::Meta::NameValue(nv) if nv.path.is_ident("path") => match &nv.value {
            syn::Expr::Lit(syn::ExprLit { lit: syn::Lit::Str(s), .. }) => Some(s.value()),
            _ => None,
        },
        _ => None,
    })
}
