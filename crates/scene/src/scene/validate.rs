//! What a tree file must satisfy beyond its types: node names valid and unique, every
//! instance naming an existing node and none inside what it instances, operators with
//! children, a tree no deeper and, its instances expanded, no larger than the compiler and
//! the evaluators take ([`MAX_DEPTH`], [`MAX_EXPANDED`]), a job section that `karstic run`
//! can carry out. A few passes over the scene and the instance graph, none recursive:
//! linear in the number of nodes.

use std::collections::HashMap;

use super::spec::{JobSpec, NodeSpec, Scene};
use crate::field::Aabb;
use crate::mesh::GridSpec;
use crate::render::camera::{Camera, check_fov, check_size};

/// Where in the text a problem lies.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Locate {
    /// The `nth` (0-based) occurrence of `key: "value"`.
    Quoted {
        /// The field, e.g. `name`.
        key: &'static str,
        /// Its value.
        value: String,
        /// Which occurrence.
        nth: usize,
    },
    /// The first field `key:` (not a mention in a comment).
    Key(&'static str),
}

/// A violated rule: what is wrong, and where to point when the text is at hand.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Problem {
    /// What is wrong.
    pub message: String,
    /// Where, if it can be found in the text.
    pub at: Option<Locate>,
}

impl Problem {
    fn quoted(key: &'static str, value: &str, nth: usize, message: String) -> Self {
        Problem {
            message,
            at: Some(Locate::Quoted {
                key,
                value: value.to_string(),
                nth,
            }),
        }
    }
}

/// Checks `scene` (see the module documentation); the first problem found.
pub fn validate(scene: &Scene) -> Result<(), Problem> {
    // A definition is used through its name: one without is silently unreachable.
    if let Some(i) = scene.defs.iter().position(|d| d.name().is_none()) {
        return Err(Problem {
            message: format!(
                "defs[{i}] ({}) has no name: nothing can use it (give it `name: \"...\"`)",
                scene.defs[i].kind()
            ),
            at: Some(Locate::Key("defs")),
        });
    }
    let graph = Graph::of(scene)?;
    graph.check_acyclic()?;
    if let Some(p) = graph.empty_operator {
        return Err(p);
    }
    check_extent(scene)?;
    if let Some(job) = &scene.job {
        check_job(job).map_err(|(key, message)| Problem {
            message: format!("job.{key}: {message}"),
            at: Some(Locate::Key(key)),
        })?;
    }
    Ok(())
}

/// The deepest a tree may nest, counting nodes inside nodes and following instances: far
/// beyond any scene written by hand or expanded from landforms, and shallow enough for the
/// compiler and the evaluators, which recurse, on any thread's stack.
pub const MAX_DEPTH: usize = 256;

/// The most nodes a tree may have once its instances are expanded. An instance is
/// evaluated wherever it is used, so instances of instances multiply the work: a
/// `Blend([Instance(next), Instance(next)])` at each of 64 levels is 2⁶⁴ evaluations.
pub const MAX_EXPANDED: u64 = 10_000_000;

/// Checks the root's depth and expanded size (instances followed) without recursion, each
/// node measured once: `(depth, size)` of a node is `1 +` the deepest and the sum of its
/// children's (an instance's child is the node it names).
fn check_extent(scene: &Scene) -> Result<(), Problem> {
    let mut named: HashMap<&str, &NodeSpec> = HashMap::new();
    for root in scene.defs.iter().chain(std::iter::once(&scene.root)) {
        root.walk(&mut |n, _| {
            if let Some(name) = n.name() {
                named.insert(name, n);
            }
        });
    }
    fn kids<'a>(n: &'a NodeSpec, named: &HashMap<&str, &'a NodeSpec>) -> Vec<&'a NodeSpec> {
        match n {
            NodeSpec::Instance(i) => named.get(i.of.as_str()).copied().into_iter().collect(),
            _ => n.children(),
        }
    }
    // A node is measured once, keyed by its address (instances share their target).
    let mut measured: HashMap<*const NodeSpec, (usize, u64)> = HashMap::new();
    // (node, its children, the next to visit, deepest and size so far)
    let mut stack = vec![(&scene.root, kids(&scene.root, &named), 0, 0usize, 1u64)];
    while let Some(top) = stack.last_mut() {
        if let Some(&k) = top.1.get(top.2) {
            top.2 += 1;
            if let Some(&(d, n)) = measured.get(&std::ptr::from_ref(k)) {
                top.3 = top.3.max(d);
                top.4 = top.4.saturating_add(n);
            } else if stack.len() >= MAX_DEPTH {
                return Err(too_deep(stack.iter().rev().find_map(|f| f.0.name())));
            } else {
                stack.push((k, kids(k, &named), 0, 0, 1));
            }
            continue;
        }
        let (n, _, _, deepest, size) = stack.pop().expect("a frame is on the stack");
        let measure = (deepest + 1, size);
        if measure.0 > MAX_DEPTH {
            let at = n
                .name()
                .or_else(|| stack.iter().rev().find_map(|f| f.0.name()));
            return Err(too_deep(at));
        }
        measured.insert(std::ptr::from_ref(n), measure);
        if let Some(parent) = stack.last_mut() {
            parent.3 = parent.3.max(measure.0);
            parent.4 = parent.4.saturating_add(measure.1);
        } else if size > MAX_EXPANDED {
            return Err(Problem {
                message: format!(
                    "the tree, its instances expanded, has {size} nodes (at most {MAX_EXPANDED}): \
                     an instance is evaluated wherever it is used, so instances of instances \
                     multiply"
                ),
                at: None,
            });
        }
    }
    Ok(())
}

/// The problem of a tree deeper than [`MAX_DEPTH`], at the named node `at` when known.
fn too_deep(at: Option<&str>) -> Problem {
    let message = format!(
        "the tree nests deeper than {MAX_DEPTH} levels (nodes inside nodes, instances \
         followed){}: karstic compiles and evaluates trees up to that depth",
        at.map_or(String::new(), |n| format!(" at node {n:?}"))
    );
    match at {
        Some(n) => Problem::quoted("name", n, 0, message),
        None => Problem { message, at: None },
    }
}

/// A node name must be a simple identifier so `NAME.PARAM` paths stay unambiguous.
fn valid_name(name: &str) -> bool {
    !name.is_empty()
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
}

/// Named nodes and the edges between them: `a → b` when `b` is the nearest named node
/// below `a`, or when an instance of `b` lies in `a`'s subtree with no named node between.
/// A subtree, following instances, contains an instance of its own node exactly when
/// this graph has a cycle (containment alone cannot make one).
struct Graph<'s> {
    names: Vec<&'s str>,
    /// Edges of each node: `(target, is an instance)`.
    edges: Vec<Vec<(usize, bool)>>,
    /// The first operator without children (reported after the names and instances).
    empty_operator: Option<Problem>,
}

impl<'s> Graph<'s> {
    fn of(scene: &'s Scene) -> Result<Self, Problem> {
        let mut index: HashMap<&str, usize> = HashMap::new();
        let mut names = Vec::new();
        let mut first_error = None;
        let mut empty = None;
        let mut instances = Vec::new();
        // (depth, named node) of the nearest named ancestors, innermost last.
        let mut owners: Vec<(usize, usize)> = Vec::new();
        let mut containment = Vec::new();
        for root in scene.defs.iter().chain(std::iter::once(&scene.root)) {
            owners.clear();
            root.walk(&mut |n, depth| {
                if first_error.is_some() {
                    return;
                }
                while owners.last().is_some_and(|&(d, _)| d >= depth) {
                    owners.pop();
                }
                let owner = owners.last().map(|&(_, o)| o);
                if empty.is_none() {
                    empty = empty_operator(n);
                }
                let mut me = owner;
                if let Some(name) = n.name() {
                    if !valid_name(name) {
                        first_error = Some(Problem::quoted(
                            "name",
                            name,
                            0,
                            format!(
                                "invalid node name {name:?}: expected letters, digits, '_' or '-'"
                            ),
                        ));
                        return;
                    }
                    if index.insert(name, names.len()).is_some() {
                        first_error = Some(Problem::quoted(
                            "name",
                            name,
                            1,
                            format!("duplicate node name {name:?}"),
                        ));
                        return;
                    }
                    if let Some(o) = owner {
                        containment.push((o, names.len()));
                    }
                    owners.push((depth, names.len()));
                    me = Some(names.len());
                    names.push(name);
                }
                if let NodeSpec::Instance(i) = n {
                    instances.push((me, i.of.as_str()));
                }
            });
        }
        if let Some(p) = first_error {
            return Err(p);
        }
        let mut edges = vec![Vec::new(); names.len()];
        for (a, b) in containment {
            edges[a].push((b, false));
        }
        for (owner, of) in instances {
            let Some(&target) = index.get(of) else {
                return Err(Problem::quoted("of", of, 0, unknown_reference(of, &names)));
            };
            if let Some(o) = owner {
                edges[o].push((target, true));
            }
        }
        Ok(Graph {
            names,
            edges,
            empty_operator: empty,
        })
    }

    /// Depth-first search without recursion (instance chains can be long): a back edge
    /// closes a cycle, which holds an instance edge; that instance is reported.
    fn check_acyclic(&self) -> Result<(), Problem> {
        #[derive(Clone, Copy, PartialEq)]
        enum Mark {
            New,
            Open,
            Done,
        }
        let mut mark = vec![Mark::New; self.names.len()];
        // (node, next edge, whether the edge into it is an instance edge)
        let mut stack: Vec<(usize, usize, bool)> = Vec::new();
        for start in 0..self.names.len() {
            if mark[start] != Mark::New {
                continue;
            }
            mark[start] = Mark::Open;
            stack.push((start, 0, false));
            while let Some(top) = stack.last_mut() {
                let (node, next) = (top.0, top.1);
                let Some(&(to, instance)) = self.edges[node].get(next) else {
                    mark[node] = Mark::Done;
                    stack.pop();
                    continue;
                };
                top.1 += 1;
                match mark[to] {
                    Mark::New => {
                        mark[to] = Mark::Open;
                        stack.push((to, 0, instance));
                    }
                    Mark::Open => return Err(self.cycle(&stack, to, instance)),
                    Mark::Done => {}
                }
            }
        }
        Ok(())
    }

    /// The problem of the cycle closed by an edge into `to` (open on `stack`).
    fn cycle(&self, stack: &[(usize, usize, bool)], to: usize, closing_instance: bool) -> Problem {
        let from = stack.iter().rposition(|s| s.0 == to).unwrap_or(0);
        // The closing edge, or an instance edge into a node of the cycle.
        let target = if closing_instance {
            to
        } else {
            stack[from + 1..].iter().find(|s| s.2).map_or(to, |s| s.0)
        };
        let name = self.names[target];
        Problem::quoted(
            "of",
            name,
            0,
            format!("instance of {name:?} is inside the node it instances (a cycle)"),
        )
    }
}

/// An n-ary operator with no child.
fn empty_operator(n: &NodeSpec) -> Option<Problem> {
    let (NodeSpec::Blend(x) | NodeSpec::Union(x) | NodeSpec::Intersection(x)) = n else {
        return None;
    };
    if !x.children.is_empty() {
        return None;
    }
    let message = |what: String| {
        format!(
            "{what} has no children: a {} needs at least one (remove it, or add a child)",
            n.kind()
        )
    };
    Some(match n.name() {
        Some(name) => Problem::quoted("name", name, 0, message(format!("{} {name:?}", n.kind()))),
        None => Problem {
            message: message(format!("an unnamed {}", n.kind())),
            at: None,
        },
    })
}

/// The message of an instance of an unknown node, listing some of the known ones.
fn unknown_reference(of: &str, names: &[&str]) -> String {
    const SHOWN: usize = 12;
    let mut known: Vec<&str> = names.iter().take(SHOWN).copied().collect();
    known.sort_unstable();
    let more = if names.len() > SHOWN {
        format!(", and {} more", names.len() - SHOWN)
    } else {
        String::new()
    };
    format!(
        "unknown node referenced: {of:?} (named nodes: {}{more})",
        known.join(", ")
    )
}

/// The job section: the region, the image and the camera as `karstic run` will use them.
/// The error names the field at fault.
fn check_job(job: &JobSpec) -> Result<(), (&'static str, String)> {
    let (w, h) = job.image;
    check_size(w, h).map_err(|e| ("image", e.to_string()))?;
    check_fov(job.fov.0).map_err(|e| ("fov", e.to_string()))?;
    if let Some(c) = job.camera {
        Camera::look_at(c.eye.0, c.target.0, job.fov.0, w, h)
            .map_err(|e| ("camera", e.to_string()))?;
    }
    if let Some(r) = job.region {
        let (min, max) = (r.min.0, r.max.0);
        if !min.cmplt(max).all() {
            return Err((
                "region",
                format!("min {min} must be below max {max} on every axis"),
            ));
        }
        GridSpec::with_cell(&Aabb::new(min, max), job.cell.0)
            .map_err(|e| ("cell", e.to_string()))?;
    }
    if let Some(sun) = job.sun
        && !(sun.elevation.0 > 0.0 && sun.elevation.0 <= 90.0)
    {
        return Err((
            "sun",
            format!(
                "elevation {}° is not above the horizon and at most 90°",
                sun.elevation.0
            ),
        ));
    }
    Ok(())
}
