//! Fill-reducing ordering of a sparse symmetric system: nested dissection of
//! its graph, with breadth-first level sets as separators.
//!
//! A cloth grid numbered row by row gives a banded matrix whose Cholesky
//! factor fills the whole band (`n · √n` entries for `n` particles). Ordering
//! each half before the line that separates them, recursively, keeps the
//! factor near `n log n` entries, and its solves as cheap.

/// Parts this small are numbered as they come.
const LEAF: usize = 32;

enum Task {
    /// Order these vertices by dissection.
    Dissect(Vec<u32>),
    /// Number these vertices now, in this order.
    Emit(Vec<u32>),
}

/// Orders the vertices `0..n` of the graph given in compressed rows
/// (`offsets`, `neighbours`; `offsets.len() == n + 1`) by nested dissection.
/// Each part is split by the middle level of a breadth-first search from a
/// far vertex (every edge joins equal or adjacent levels, so that level
/// separates the two sides); both sides are ordered first and the separator
/// last. Returns the order: position → vertex.
pub(crate) fn nested_dissection(offsets: &[usize], neighbours: &[u32]) -> Vec<u32> {
    let n = offsets.len().saturating_sub(1);
    let mut order = Vec::with_capacity(n);
    let mut part = vec![0u32; n];
    let mut level = vec![u32::MAX; n];
    let mut queue = Vec::with_capacity(n);
    let mut label = 0u32;
    let mut tasks = vec![Task::Dissect((0..n as u32).collect())];
    while let Some(task) = tasks.pop() {
        let nodes = match task {
            Task::Emit(nodes) => {
                order.extend(nodes);
                continue;
            }
            Task::Dissect(nodes) if nodes.len() <= LEAF => {
                order.extend(nodes);
                continue;
            }
            Task::Dissect(nodes) => nodes,
        };
        label += 1;
        for &v in &nodes {
            part[v as usize] = label;
        }
        let bfs = |start: u32, level: &mut [u32], queue: &mut Vec<u32>| {
            for &v in &nodes {
                level[v as usize] = u32::MAX;
            }
            queue.clear();
            queue.push(start);
            level[start as usize] = 0;
            let mut head = 0;
            while head < queue.len() {
                let v = queue[head] as usize;
                head += 1;
                for &w in &neighbours[offsets[v]..offsets[v + 1]] {
                    let w = w as usize;
                    if part[w] == label && level[w] == u32::MAX {
                        level[w] = level[v] + 1;
                        queue.push(w as u32);
                    }
                }
            }
        };
        // Two searches: the second starts from the vertex farthest from the first.
        bfs(nodes[0], &mut level, &mut queue);
        let far = queue[queue.len() - 1];
        bfs(far, &mut level, &mut queue);
        if queue.len() < nodes.len() {
            // Disconnected: the component reached, and the rest, separately.
            let rest = nodes
                .iter()
                .copied()
                .filter(|&v| level[v as usize] == u32::MAX)
                .collect();
            tasks.push(Task::Dissect(rest));
            tasks.push(Task::Dissect(queue.clone()));
            continue;
        }
        let deepest = level[queue[queue.len() - 1] as usize];
        if deepest < 2 {
            order.extend(nodes);
            continue;
        }
        // The level at which half the vertices have been reached.
        let mut counts = vec![0usize; deepest as usize + 1];
        for &v in &nodes {
            counts[level[v as usize] as usize] += 1;
        }
        let mut middle = 1;
        let mut reached = 0;
        for (l, &c) in counts.iter().enumerate() {
            reached += c;
            if 2 * reached >= nodes.len() {
                middle = l as u32;
                break;
            }
        }
        let middle = middle.clamp(1, deepest - 1);
        let (mut near, mut far_side, mut separator) = (Vec::new(), Vec::new(), Vec::new());
        for &v in &queue {
            let l = level[v as usize];
            if l < middle {
                near.push(v);
            } else if l > middle {
                far_side.push(v);
            } else {
                separator.push(v);
            }
        }
        tasks.push(Task::Emit(separator));
        tasks.push(Task::Dissect(far_side));
        tasks.push(Task::Dissect(near));
    }
    order
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `w × h` grid with its four-neighbour edges.
    fn grid(w: usize, h: usize) -> (Vec<usize>, Vec<u32>) {
        let mut offsets = vec![0];
        let mut neighbours = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let i = (y * w + x) as u32;
                if x > 0 {
                    neighbours.push(i - 1);
                }
                if x + 1 < w {
                    neighbours.push(i + 1);
                }
                if y > 0 {
                    neighbours.push(i - w as u32);
                }
                if y + 1 < h {
                    neighbours.push(i + w as u32);
                }
                offsets.push(neighbours.len());
            }
        }
        (offsets, neighbours)
    }

    #[test]
    fn every_vertex_once() {
        for (w, h) in [(1, 1), (3, 2), (40, 40), (64, 17)] {
            let (o, nb) = grid(w, h);
            let mut order = nested_dissection(&o, &nb);
            assert_eq!(order.len(), w * h);
            order.sort_unstable();
            assert!(order.iter().enumerate().all(|(i, &v)| v as usize == i));
        }
        // Two components and an isolated vertex.
        let order = nested_dissection(&[0, 1, 2, 2], &[1, 0]);
        assert_eq!(order.len(), 3);
    }

    /// Nonzeros of the Cholesky factor of the grid's matrix in this order.
    fn fill(o: &[usize], nb: &[u32], order: &[u32]) -> usize {
        use nalgebra_sparse::factorization::CscSymbolicCholesky;
        use nalgebra_sparse::pattern::SparsityPattern;
        let n = order.len();
        let mut pos = vec![0usize; n];
        for (p, &v) in order.iter().enumerate() {
            pos[v as usize] = p;
        }
        let mut cols: Vec<Vec<usize>> = vec![Vec::new(); n];
        for v in 0..n {
            cols[pos[v]].push(pos[v]);
            for &w in &nb[o[v]..o[v + 1]] {
                cols[pos[v]].push(pos[w as usize]);
            }
        }
        let mut offsets = vec![0];
        let mut indices = Vec::new();
        for mut c in cols {
            c.sort_unstable();
            indices.extend(c);
            offsets.push(indices.len());
        }
        let pattern = SparsityPattern::try_from_offsets_and_indices(n, n, offsets, indices)
            .expect("valid pattern");
        CscSymbolicCholesky::factor(pattern).l_pattern().nnz()
    }

    #[test]
    fn the_factor_fills_far_less_than_the_band() {
        let (o, nb) = grid(48, 48);
        let natural: Vec<u32> = (0..48 * 48).collect();
        let banded = fill(&o, &nb, &natural);
        let dissected = fill(&o, &nb, &nested_dissection(&o, &nb));
        assert!(
            dissected * 2 < banded,
            "nested dissection {dissected} nonzeros, row order {banded}"
        );
    }
}
