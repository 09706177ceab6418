//! The import graph among the child modules of one module (the engine's top-level modules are the root's
//! children), its cycles (strongly connected components), and a readable listing of both.

use super::module_tree::{ModuleTree, Site, Target};
use std::collections::{BTreeMap, BTreeSet};

/// Who names whom among the children of one module, with every site that does.
pub struct ImportGraph {
    /// The parent module, e.g. `["render"]`; empty for the crate root.
    pub parent: Vec<String>,
    pub nodes: BTreeSet<String>,
    /// (from child, to child) -> the places in `from`'s files that name `to`.
    pub edges: BTreeMap<(String, String), Vec<Site>>,
}

impl ImportGraph {
    /// The graph among `parent`'s children: an edge a -> b for every path in a's subtree that names b's
    /// subtree (directly, through `super::`, or through a re-export in `parent`).
    pub fn among_children(tree: &ModuleTree, parent: &[String]) -> Self {
        let nodes = tree.children(parent);
        let child_of = |path: &[String]| -> Option<String> {
            let name = path.strip_prefix(parent)?.first()?;
            nodes.contains(name).then(|| name.clone())
        };
        let mut edges: BTreeMap<(String, String), Vec<Site>> = BTreeMap::new();
        for used in tree.uses() {
            let Target::Internal(target) = &used.target else {
                continue;
            };
            if let (Some(from), Some(to)) = (child_of(&used.from), child_of(target))
                && from != to
            {
                edges.entry((from, to)).or_default().push(used.site);
            }
        }
        for sites in edges.values_mut() {
            sites.sort();
            sites.dedup();
        }
        ImportGraph {
            parent: parent.to_vec(),
            nodes,
            edges,
        }
    }

    /// A child's qualified name, e.g. `render::denoise`.
    pub fn qualified(&self, child: &str) -> String {
        self.parent
            .iter()
            .map(String::as_str)
            .chain([child])
            .collect::<Vec<_>>()
            .join("::")
    }

    fn successors(&self, node: &str) -> impl Iterator<Item = &str> {
        self.edges
            .keys()
            .filter(move |(from, _)| from == node)
            .map(|(_, to)| to.as_str())
    }

    /// Strongly connected components of more than one module (Tarjan): each is a set of modules that import
    /// each other in a circle.
    pub fn cycles(&self) -> Vec<BTreeSet<String>> {
        struct Tarjan<'g> {
            graph: &'g ImportGraph,
            index: BTreeMap<&'g str, usize>,
            low: BTreeMap<&'g str, usize>,
            stack: Vec<&'g str>,
            on_stack: BTreeSet<&'g str>,
            components: Vec<BTreeSet<String>>,
        }
        impl<'g> Tarjan<'g> {
            fn visit(&mut self, v: &'g str) {
                let i = self.index.len();
                self.index.insert(v, i);
                self.low.insert(v, i);
                self.stack.push(v);
                self.on_stack.insert(v);
                for w in self.graph.successors(v) {
                    if !self.index.contains_key(w) {
                        self.visit(w);
                        let low = self.low[v].min(self.low[w]);
                        self.low.insert(v, low);
                    } else if self.on_stack.contains(w) {
                        let low = self.low[v].min(self.index[w]);
                        self.low.insert(v, low);
                    }
                }
                if self.low[v] == self.index[v] {
                    let mut component = BTreeSet::new();
                    while let Some(w) = self.stack.pop() {
                        self.on_stack.remove(w);
                        component.insert(w.to_string());
                        if w == v {
                            break;
                        }
                    }
                    if component.len() > 1 {
                        self.components.push(component);
                    }
                }
            }
        }
        let mut tarjan = Tarjan {
            graph: self,
            index: BTreeMap::new(),
            low: BTreeMap::new(),
            stack: Vec::new(),
            on_stack: BTreeSet::new(),
            components: Vec::new(),
        };
        for node in &self.nodes {
            if !tarjan.index.contains_key(node.as_str()) {
                tarjan.visit(node);
            }
        }
        tarjan.components
    }

    /// One circle through `component` (its first module back to itself, shortest), each step with the files
    /// and lines that make it.
    pub fn explain(&self, component: &BTreeSet<String>) -> String {
        let start = component.first().expect("a component has modules");
        // Breadth-first inside the component, from `start` until an edge leads back to it.
        let mut came_from: BTreeMap<&str, &str> = BTreeMap::new();
        let mut queue = std::collections::VecDeque::from([start.as_str()]);
        let mut last = None;
        'search: while let Some(v) = queue.pop_front() {
            for w in self.successors(v).filter(|w| component.contains(*w)) {
                if w == start {
                    last = Some(v);
                    break 'search;
                }
                if !came_from.contains_key(w) {
                    came_from.insert(w, v);
                    queue.push_back(w);
                }
            }
        }
        let mut back = Vec::new();
        let mut v = last.expect("a strongly connected component has a circle");
        while v != start {
            back.push(v);
            v = came_from[v];
        }
        let circle: Vec<&str> = std::iter::once(start.as_str())
            .chain(back.into_iter().rev())
            .chain([start.as_str()])
            .collect();
        let mut text = circle
            .iter()
            .map(|m| self.qualified(m))
            .collect::<Vec<_>>()
            .join(" -> ");
        for step in circle.windows(2) {
            let sites = &self.edges[&(step[0].to_string(), step[1].to_string())];
            text += &format!("\n    {} -> {}: {}", step[0], step[1], list_sites(sites));
        }
        text
    }

    /// One line per module: what it imports, e.g. `  render -> bvh, camera, gpu`.
    pub fn listing(&self) -> String {
        let mut text = String::new();
        for node in &self.nodes {
            let targets: Vec<&str> = self.successors(node).collect();
            let targets = if targets.is_empty() {
                "(none)".to_string()
            } else {
                targets.join(", ")
            };
            text += &format!("  {node} -> {targets}\n");
        }
        text
    }
}

/// The first few sites of a list, and how many more.
pub fn list_sites(sites: &[Site]) -> String {
    const SHOWN: usize = 4;
    let mut text = sites
        .iter()
        .take(SHOWN)
        .map(Site::to_string)
        .collect::<Vec<_>>()
        .join(", ");
    if sites.len() > SHOWN {
        text += &format!(" and {} more", sites.len() - SHOWN);
    }
    text
}
