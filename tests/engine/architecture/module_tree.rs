//! A crate's modules as its `src/` file tree lays them out, and every path each file names (use trees, paths in
//! code and types, paths inside macro calls), resolved against that tree through `use` re-exports: what the
//! import-graph checks read. Parsed with syn, so comments and string literals never count.

use proc_macro2::{TokenStream, TokenTree};
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use syn::spanned::Spanned;
use syn::visit::Visit;

/// A module's path from the crate root, e.g. `["render", "denoise"]`; empty for the root.
pub type ModulePath = Vec<String>;

/// Where a file names a path.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct Site {
    /// As the tree was given it (e.g. `engine/src/render/mod.rs`).
    pub file: PathBuf,
    pub line: usize,
}

impl std::fmt::Display for Target {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Target::Internal(path) => write!(f, "crate::{}", path.join("::")),
            Target::External(path) => write!(f, "{}", path.join("::")),
        }
    }
}

impl std::fmt::Display for Site {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}:{}", self.file.display(), self.line)
    }
}

/// A path as written in a file, with the module it is written in (inline `mod` blocks included).
#[derive(Clone, Debug)]
struct Reference {
    site: Site,
    from: ModulePath,
    /// Segments as written, `crate` / `super` / `self` included; `::`-prefixed paths start with `::`.
    written: Vec<String>,
}

/// What a written path names once resolved.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Target {
    /// A path inside this crate, from its root (re-exports followed to where the item lives).
    Internal(Vec<String>),
    /// Another crate's item, e.g. `["wgpu", "Buffer"]`.
    External(Vec<String>),
}

/// A resolved reference: where it is written, from which module, and what it names.
#[derive(Clone, Debug)]
pub struct Use {
    pub site: Site,
    pub from: ModulePath,
    pub target: Target,
}

pub struct ModuleTree {
    /// Every module, with the file that defines it (inline modules have their enclosing file).
    modules: BTreeMap<ModulePath, PathBuf>,
    /// Modules written inline (`mod tests { ... }`): part of their file for the graphs.
    inline: BTreeSet<ModulePath>,
    /// Names each module brings into scope with a module-level `use`: name -> the path as written there.
    imports: BTreeMap<ModulePath, BTreeMap<String, Vec<String>>>,
    references: Vec<Reference>,
}

impl ModuleTree {
    /// Reads every `.rs` file under `src_dir` (a crate's `src/`); sites and errors name each file as
    /// `shown_as` joined with its path inside `src_dir`.
    pub fn load(src_dir: &Path, shown_as: &Path) -> Result<Self, String> {
        let mut sources = Vec::new();
        let mut stack = vec![src_dir.to_path_buf()];
        while let Some(dir) = stack.pop() {
            let entries = std::fs::read_dir(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
            for entry in entries {
                let path = entry.map_err(|e| format!("{}: {e}", dir.display()))?.path();
                if path.is_dir() {
                    stack.push(path);
                } else if path.extension().is_some_and(|e| e == "rs") {
                    let text = std::fs::read_to_string(&path)
                        .map_err(|e| format!("{}: {e}", path.display()))?;
                    let relative = path.strip_prefix(src_dir).expect("under src_dir");
                    sources.push((relative.to_path_buf(), text));
                }
            }
        }
        Self::build(&sources, shown_as)
    }

    /// Builds the tree from `(path relative to src/, text)` pairs: `lib.rs` / `main.rs` is the root, `x/mod.rs`
    /// and `x.rs` are module `x`, `x/y.rs` is `x::y`.
    pub fn from_sources(sources: &[(PathBuf, String)]) -> Result<Self, String> {
        Self::build(sources, Path::new(""))
    }

    fn build(sources: &[(PathBuf, String)], shown_under: &Path) -> Result<Self, String> {
        let mut tree = ModuleTree {
            modules: BTreeMap::new(),
            inline: BTreeSet::new(),
            imports: BTreeMap::new(),
            references: Vec::new(),
        };
        for (file, _) in sources {
            tree.modules.insert(module_of(file), file.clone());
        }
        for (file, text) in sources {
            let shown = shown_under.join(file);
            let ast = syn::parse_file(text).map_err(|e| {
                let at = e.span().start();
                format!("{}:{}:{}: {e}", shown.display(), at.line, at.column + 1)
            })?;
            let mut collector = Collector {
                file: &shown,
                stack: vec![module_of(file)],
                block_depth: 0,
                tree: &mut tree,
            };
            collector.visit_file(&ast);
        }
        Ok(tree)
    }

    /// Every module with a file of its own, the root included.
    pub fn modules(&self) -> impl Iterator<Item = &ModulePath> {
        self.modules.keys().filter(|m| !self.inline.contains(*m))
    }

    /// The names of `parent`'s child modules that have files of their own.
    pub fn children(&self, parent: &[String]) -> BTreeSet<String> {
        self.modules()
            .filter(|m| m.len() == parent.len() + 1 && m.starts_with(parent))
            .map(|m| m[parent.len()].clone())
            .collect()
    }

    /// Every reference in the crate, resolved.
    pub fn uses(&self) -> Vec<Use> {
        self.references
            .iter()
            .filter_map(|r| {
                Some(Use {
                    site: r.site.clone(),
                    from: r.from.clone(),
                    target: self.resolve(&r.from, &r.written, 0)?,
                })
            })
            .collect()
    }

    /// What `written`, seen from module `from`, names; `None` for a local name (a type parameter, a variable,
    /// an item of the module itself) that leads nowhere.
    fn resolve(&self, from: &[String], written: &[String], depth: usize) -> Option<Target> {
        let first = written.first()?;
        let absolute: Vec<String> = match first.as_str() {
            "::" => return Some(Target::External(written[1..].to_vec())),
            "crate" => written[1..].to_vec(),
            "self" => [from, &written[1..]].concat(),
            "super" => {
                let ups = written.iter().take_while(|s| *s == "super").count();
                let base = from.get(..from.len().checked_sub(ups)?)?;
                [base, &written[ups..]].concat()
            }
            _ => {
                // Relative: a child module, else a name a `use` brought into this module, else another crate.
                let child = [from, &written[..1]].concat();
                if self.modules.contains_key(&child) {
                    [from, written].concat()
                } else if let Some(imported) = self.imports.get(from).and_then(|i| i.get(first)) {
                    // `use wgpu;` binds `wgpu` to itself: another crate.
                    if imported.as_slice() == &written[..1] {
                        return Some(Target::External(written.to_vec()));
                    }
                    if depth > 16 {
                        return None;
                    }
                    let through = [imported.as_slice(), &written[1..]].concat();
                    return self.resolve(from, &through, depth + 1);
                } else if written.len() >= 2 {
                    return Some(Target::External(written.to_vec()));
                } else {
                    return None;
                }
            }
        };
        self.follow_reexports(absolute, depth)
    }

    /// Walks `path` down the module tree; where a segment is not a child module but a name its module imports
    /// (`pub use settings::RenderSettings`, or a private `use` its children reach through `super::`), continues
    /// from what that import names.
    fn follow_reexports(&self, path: Vec<String>, depth: usize) -> Option<Target> {
        let mut module = Vec::new();
        for (i, segment) in path.iter().enumerate() {
            let child = [module.as_slice(), std::slice::from_ref(segment)].concat();
            if self.modules.contains_key(&child) {
                module = child;
                continue;
            }
            return match self.imports.get(&module).and_then(|m| m.get(segment)) {
                Some(imported) if depth <= 16 => {
                    let through = [imported.as_slice(), &path[i + 1..]].concat();
                    self.resolve(&module, &through, depth + 1)
                }
                _ => Some(Target::Internal(path)),
            };
        }
        Some(Target::Internal(path))
    }
}

/// `render/denoise.rs` -> `["render", "denoise"]`; `lib.rs`, `main.rs` -> root; `x/mod.rs` -> `["x"]`.
fn module_of(file: &Path) -> ModulePath {
    let mut parts: Vec<String> = file
        .iter()
        .map(|c| c.to_string_lossy().into_owned())
        .collect();
    let last = parts.pop().unwrap_or_default();
    let stem = last.strip_suffix(".rs").unwrap_or(&last);
    let at_root = parts.is_empty() && (stem == "lib" || stem == "main");
    if stem != "mod" && !at_root {
        parts.push(stem.to_string());
    }
    parts
}

struct Collector<'a> {
    file: &'a Path,
    /// The module being visited: the file's, then any inline `mod` inside it.
    stack: Vec<ModulePath>,
    /// Inside a block, a `use` imports into the block, not the module.
    block_depth: usize,
    tree: &'a mut ModuleTree,
}

impl Collector<'_> {
    fn module(&self) -> &ModulePath {
        self.stack.last().expect("the file's module")
    }

    fn record(&mut self, written: Vec<String>, line: usize) {
        self.tree.references.push(Reference {
            site: Site {
                file: self.file.to_path_buf(),
                line,
            },
            from: self.module().clone(),
            written,
        });
    }

    /// Paths inside a macro call's tokens (`format!("{}", crate::x::f())`): runs of `ident :: ident ...`.
    fn scan_tokens(&mut self, tokens: TokenStream) {
        let tokens: Vec<TokenTree> = tokens.into_iter().collect();
        let is_colon =
            |i: usize| matches!(tokens.get(i), Some(TokenTree::Punct(p)) if p.as_char() == ':');
        let mut i = 0;
        while i < tokens.len() {
            match &tokens[i] {
                TokenTree::Group(g) => self.scan_tokens(g.stream()),
                TokenTree::Ident(first) => {
                    let leading = i >= 2 && is_colon(i - 1) && is_colon(i - 2);
                    let mut written: Vec<String> =
                        leading.then(|| "::".to_string()).into_iter().collect();
                    written.push(first.to_string());
                    let line = first.span().start().line;
                    while is_colon(i + 1) && is_colon(i + 2) {
                        let Some(TokenTree::Ident(next)) = tokens.get(i + 3) else {
                            break;
                        };
                        written.push(next.to_string());
                        i += 3;
                    }
                    if written.len() >= 2 {
                        self.record(written, line);
                    }
                }
                _ => {}
            }
            i += 1;
        }
    }
}

impl<'ast> Visit<'ast> for Collector<'_> {
    fn visit_item_mod(&mut self, item: &'ast syn::ItemMod) {
        if let Some((_, items)) = &item.content {
            let inner = [self.module().as_slice(), &[item.ident.to_string()]].concat();
            self.tree
                .modules
                .entry(inner.clone())
                .or_insert_with(|| self.file.to_path_buf());
            self.tree.inline.insert(inner.clone());
            self.stack.push(inner);
            let outer_depth = std::mem::replace(&mut self.block_depth, 0);
            for item in items {
                self.visit_item(item);
            }
            self.block_depth = outer_depth;
            self.stack.pop();
        }
    }

    fn visit_block(&mut self, block: &'ast syn::Block) {
        self.block_depth += 1;
        syn::visit::visit_block(self, block);
        self.block_depth -= 1;
    }

    fn visit_item_use(&mut self, item: &'ast syn::ItemUse) {
        let mut prefix = Vec::new();
        if item.leading_colon.is_some() {
            prefix.push("::".to_string());
        }
        let mut flat = Vec::new();
        flatten_use(&item.tree, &mut prefix, &mut flat);
        for (written, name, line) in flat {
            if self.block_depth == 0
                && let Some(name) = name
            {
                let module = self.module().clone();
                self.tree
                    .imports
                    .entry(module)
                    .or_default()
                    .insert(name, written.clone());
            }
            self.record(written, line);
        }
    }

    fn visit_path(&mut self, path: &'ast syn::Path) {
        let mut written: Vec<String> = Vec::new();
        if path.leading_colon.is_some() {
            written.push("::".to_string());
        }
        written.extend(path.segments.iter().map(|s| s.ident.to_string()));
        if written.len() >= 2 {
            self.record(written, path.span().start().line);
        }
        syn::visit::visit_path(self, path);
    }

    fn visit_macro(&mut self, mac: &'ast syn::Macro) {
        syn::visit::visit_macro(self, mac);
        self.scan_tokens(mac.tokens.clone());
    }
}

/// Every leaf of a use tree: (full path as written, the name it binds if any, line).
fn flatten_use(
    tree: &syn::UseTree,
    prefix: &mut Vec<String>,
    out: &mut Vec<(Vec<String>, Option<String>, usize)>,
) {
    let line = tree.span().start().line;
    match tree {
        syn::UseTree::Path(p) => {
            prefix.push(p.ident.to_string());
            flatten_use(&p.tree, prefix, out);
            prefix.pop();
        }
        syn::UseTree::Name(n) if n.ident == "self" => {
            // `use a::b::{self, c}` binds `b`.
            out.push((prefix.clone(), prefix.last().cloned(), line));
        }
        syn::UseTree::Name(n) => {
            let name = n.ident.to_string();
            out.push((
                [prefix.as_slice(), std::slice::from_ref(&name)].concat(),
                Some(name),
                line,
            ));
        }
        syn::UseTree::Rename(r) => {
            let path = [prefix.as_slice(), &[r.ident.to_string()]].concat();
            out.push((path, Some(r.rename.to_string()), line));
        }
        // A glob binds names the tree does not know; the path itself is still a dependency.
        syn::UseTree::Glob(_) => out.push((prefix.clone(), None, line)),
        syn::UseTree::Group(g) => {
            for tree in &g.items {
                flatten_use(tree, prefix, out);
            }
        }
    }
}
