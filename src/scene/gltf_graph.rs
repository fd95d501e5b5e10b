//! The glTF node graph: acyclic, bounded once expanded, and a forest.
//!
//! glTF 2.0 (§3.5.2) makes the nodes disjoint trees: a node has at most one
//! parent, a scene's roots have none, and no list names a node twice. The
//! Khronos validator calls a file that breaks this invalid, and the loader
//! refuses it ([`check_forest`]) after [`check_graph`], whose messages name
//! cycles and explosive sharing more precisely.
//!
//! A node listed as the child of several parents is instantiated once per
//! path, so 40 levels of shared children expand to 2^40 nodes. The loader
//! walks every path, so the instances are counted first, bottom-up with
//! saturating sums (one pass over the nodes, no expansion), and a graph
//! over [`MAX_NODE_INSTANCES`] nodes or [`MAX_INSTANCED_TRIANGLES`]
//! triangles is refused before any vertex is transformed; a node's GPU
//! instances (`EXT_mesh_gpu_instancing`) count as node instances, and
//! multiply its mesh's triangles.

use super::gltf_checks::{label, MAX_INSTANCED_TRIANGLES, MAX_NODE_INSTANCES};
use crate::error::{Error, Result};
use gltf::json::{
    mesh::{Mode, Semantic},
    validation::Checked,
    Root,
};

/// Triangles one instance of mesh `m` adds (from the accessors' counts).
fn mesh_triangles(root: &Root, m: usize) -> u64 {
    root.meshes[m]
        .primitives
        .iter()
        .map(|p| {
            let count = match p.indices {
                Some(i) => root.accessors[i.value()].count.0,
                None => p
                    .attributes
                    .get(&Checked::Valid(Semantic::Positions))
                    .map_or(0, |a| root.accessors[a.value()].count.0),
            };
            match p.mode {
                Checked::Valid(Mode::TriangleStrip | Mode::TriangleFan) => count.saturating_sub(2),
                Checked::Valid(Mode::Triangles) => count / 3,
                _ => 0,
            }
        })
        .fold(0u64, u64::saturating_add)
}

/// Refuses cycles and explosive sharing. Node, mesh and child indices were
/// checked by [`super::gltf_checks::check_document`] before this runs.
pub(super) fn check_graph(root: &Root) -> Result<()> {
    let n = root.nodes.len();
    // Per node: (instances, triangles) of its subtree, once finished.
    let mut done: Vec<Option<(u64, u64)>> = vec![None; n];
    let mut on_path = vec![false; n];
    for start in 0..n {
        if done[start].is_some() {
            continue;
        }
        // Iterative post-order DFS: a 100 000-deep chain must not overflow the stack.
        let mut stack: Vec<(usize, usize)> = vec![(start, 0)];
        on_path[start] = true;
        while let Some(&mut (node, ref mut next)) = stack.last_mut() {
            let children = root.nodes[node].children.as_deref().unwrap_or(&[]);
            if let Some(c) = children.get(*next) {
                *next += 1;
                let c = c.value();
                if on_path[c] {
                    return Err(Error::InvalidScene(format!(
                        "{} is its own ancestor (the node hierarchy has a cycle)",
                        label("node", c, root.nodes[c].name.as_deref())
                    )));
                }
                if done[c].is_none() {
                    on_path[c] = true;
                    stack.push((c, 0));
                }
                continue;
            }
            // A node's GPU instances count as node instances too.
            let copies = super::gltf_instancing::instance_count(root, node)?;
            let mut nodes = copies;
            let mut tris = root.nodes[node].mesh.map_or(0, |m| {
                mesh_triangles(root, m.value()).saturating_mul(copies)
            });
            for c in children {
                let (cn, ct) = done[c.value()].unwrap_or_default();
                nodes = nodes.saturating_add(cn);
                tris = tris.saturating_add(ct);
            }
            done[node] = Some((nodes, tris));
            on_path[node] = false;
            stack.pop();
        }
    }
    for (si, s) in root.scenes.iter().enumerate() {
        let (mut nodes, mut tris) = (0u64, 0u64);
        for r in &s.nodes {
            let (cn, ct) = done[r.value()].unwrap_or_default();
            nodes = nodes.saturating_add(cn);
            tris = tris.saturating_add(ct);
        }
        let name = label("scene", si, s.name.as_deref());
        if nodes > MAX_NODE_INSTANCES {
            return Err(Error::InvalidScene(format!(
                "{name} expands to {nodes} node instances (shared children), over the limit of {MAX_NODE_INSTANCES}"
            )));
        }
        if tris > MAX_INSTANCED_TRIANGLES {
            return Err(Error::InvalidScene(format!(
                "{name} expands to {tris} triangles, over the limit of {MAX_INSTANCED_TRIANGLES}"
            )));
        }
    }
    Ok(())
}

/// Refuses a node with two parents, a child listed twice, a scene root that
/// is some node's child, and a root listed twice (it would load twice).
pub(super) fn check_forest(root: &Root) -> Result<()> {
    let mut parent: Vec<Option<usize>> = vec![None; root.nodes.len()];
    for (p, node) in root.nodes.iter().enumerate() {
        for c in node.children.iter().flatten() {
            let c = c.value();
            let child = label("node", c, root.nodes[c].name.as_deref());
            match parent[c] {
                Some(q) if q == p => {
                    return Err(Error::InvalidScene(format!(
                        "{child} is listed twice among the children of {}",
                        label("node", p, node.name.as_deref())
                    )))
                }
                Some(q) => {
                    return Err(Error::InvalidScene(format!(
                        "{child} is a child of both {} and {}: glTF nodes form trees \
                         (to instance a mesh, refer to it from several nodes)",
                        label("node", q, root.nodes[q].name.as_deref()),
                        label("node", p, node.name.as_deref())
                    )))
                }
                None => parent[c] = Some(p),
            }
        }
    }
    for (si, s) in root.scenes.iter().enumerate() {
        let scene = label("scene", si, s.name.as_deref());
        let mut seen = vec![false; root.nodes.len()];
        for r in &s.nodes {
            let r = r.value();
            let node = label("node", r, root.nodes[r].name.as_deref());
            if std::mem::replace(&mut seen[r], true) {
                return Err(Error::InvalidScene(format!(
                    "{scene} lists {node} twice among its roots"
                )));
            }
            if let Some(p) = parent[r] {
                return Err(Error::InvalidScene(format!(
                    "{scene} lists {node} as a root, but it is a child of {}",
                    label("node", p, root.nodes[p].name.as_deref())
                )));
            }
        }
    }
    Ok(())
}
