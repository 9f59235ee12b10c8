//! A directed graph of files, its strongly connected components (Tarjan) and one shortest
//! cycle through each file of a component. Used by `cycles.rs`.

use std::collections::{BTreeMap, BTreeSet, VecDeque};

#[derive(Default)]
pub struct Graph {
    pub nodes: Vec<String>,
    index: BTreeMap<String, usize>,
    /// `(from, to)` -> the first place that makes the edge, e.g. `line 12: super::bus::Bus`.
    pub edges: BTreeMap<(usize, usize), String>,
}

impl Graph {
    pub fn node(&mut self, name: &str) -> usize {
        if let Some(&i) = self.index.get(name) {
            return i;
        }
        self.nodes.push(name.to_owned());
        self.index.insert(name.to_owned(), self.nodes.len() - 1);
        self.nodes.len() - 1
    }

    pub fn edge(&mut self, from: usize, to: usize, why: impl FnOnce() -> String) {
        if from != to {
            self.edges.entry((from, to)).or_insert_with(why);
        }
    }

    fn successors(&self) -> Vec<Vec<usize>> {
        let mut next = vec![Vec::new(); self.nodes.len()];
        for &(from, to) in self.edges.keys() {
            next[from].push(to);
        }
        next
    }

    /// Components of more than one node (a file never depends on itself here).
    pub fn components(&self) -> Vec<Vec<usize>> {
        let next = self.successors();
        let mut tarjan = Tarjan { next: &next, index: vec![usize::MAX; next.len()], low: vec![0; next.len()], on_stack: vec![false; next.len()], stack: Vec::new(), counter: 0, out: Vec::new() };
        for v in 0..next.len() {
            if tarjan.index[v] == usize::MAX {
                tarjan.visit(v);
            }
        }
        let mut out: Vec<Vec<usize>> = tarjan.out.into_iter().filter(|c| c.len() > 1).collect();
        for c in &mut out {
            c.sort_by(|&a, &b| self.nodes[a].cmp(&self.nodes[b]));
        }
        out.sort_by(|a, b| self.nodes[a[0]].cmp(&self.nodes[b[0]]));
        out
    }

    /// For each node of `component`, a shortest cycle through it (breadth-first inside the
    /// component), each distinct cycle once, starting at its first file by name.
    pub fn cycles(&self, component: &[usize]) -> Vec<Vec<usize>> {
        let next = self.successors();
        let inside: BTreeSet<usize> = component.iter().copied().collect();
        let mut seen = BTreeSet::new();
        let mut out = Vec::new();
        for &start in component {
            let mut parent = BTreeMap::new();
            let mut queue = VecDeque::from([start]);
            let mut last = None;
            'search: while let Some(v) = queue.pop_front() {
                for &w in &next[v] {
                    if w == start {
                        last = Some(v);
                        break 'search;
                    }
                    if inside.contains(&w) && !parent.contains_key(&w) {
                        parent.insert(w, v);
                        queue.push_back(w);
                    }
                }
            }
            let Some(mut v) = last else { continue };
            let mut cycle = vec![v];
            while v != start {
                v = parent[&v];
                cycle.push(v);
            }
            cycle.reverse();
            let first = (0..cycle.len()).min_by(|&a, &b| self.nodes[cycle[a]].cmp(&self.nodes[cycle[b]])).unwrap_or(0);
            cycle.rotate_left(first);
            if seen.insert(cycle.clone()) {
                out.push(cycle);
            }
        }
        out
    }
}

struct Tarjan<'g> {
    next: &'g [Vec<usize>],
    index: Vec<usize>,
    low: Vec<usize>,
    on_stack: Vec<bool>,
    stack: Vec<usize>,
    counter: usize,
    out: Vec<Vec<usize>>,
}

impl Tarjan<'_> {
    fn visit(&mut self, v: usize) {
        self.index[v] = self.counter;
        self.low[v] = self.counter;
        self.counter += 1;
        self.stack.push(v);
        self.on_stack[v] = true;
        for &w in &self.next[v] {
            if self.index[w] == usize::MAX {
                self.visit(w);
                self.low[v] = self.low[v].min(self.low[w]);
            } else if self.on_stack[w] {
                self.low[v] = self.low[v].min(self.index[w]);
            }
        }
        if self.low[v] == self.index[v] {
            let mut component = Vec::new();
            loop {
                let w = self.stack.pop().expect("on the stack");
                self.on_stack[w] = false;
                component.push(w);
                if w == v {
                    break;
                }
            }
            self.out.push(component);
        }
    }
}
