//! The paths pending at one bounce depth, kept as the chunks that the
//! batches wrote them in: a batch's children join the queue as its vector,
//! moved, not copied, and a wave leaves it as whole chunks (plus at most one
//! split chunk). Appending children and draining a wave were serial copies
//! between the wave's parallel steps (48 bytes a path, twice).
//!
//! The queue's order is the order of its paths as if the chunks were one
//! array, so which paths a wave takes (the last `n`) does not depend on the
//! chunks' sizes, which depend on the batch size.

use super::wave::PathState;

/// Pending paths, in chunks.
#[derive(Clone, Debug, Default)]
pub(super) struct PathQueue {
    chunks: Vec<Vec<PathState>>,
    len: usize,
}

impl PathQueue {
    /// Paths in the queue.
    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Appends `chunk`'s paths (moved, not copied).
    pub fn push_chunk(&mut self, chunk: Vec<PathState>) {
        if !chunk.is_empty() {
            self.len += chunk.len();
            self.chunks.push(chunk);
        }
    }

    /// Moves the last `n` paths (all of them when fewer are pending) to the
    /// end of `out`, as chunks in queue order.
    pub fn take_last(&mut self, n: usize, out: &mut Vec<Vec<PathState>>) {
        let mut need = n.min(self.len);
        self.len -= need;
        let first = out.len();
        while need > 0 {
            let Some(mut chunk) = self.chunks.pop() else {
                break; // unreachable: `len` counts the chunks' paths
            };
            if chunk.len() > need {
                let tail = chunk.split_off(chunk.len() - need);
                self.chunks.push(chunk);
                chunk = tail;
            }
            need -= chunk.len();
            out.push(chunk);
        }
        out[first..].reverse();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn path(key: u64) -> PathState {
        PathState {
            origin: Vec3::ZERO,
            direction: Vec3::Z,
            power: Vec3::ONE,
            key,
            specular_chain: true,
        }
    }

    fn keys(chunks: &[Vec<PathState>]) -> Vec<u64> {
        chunks.iter().flatten().map(|p| p.key).collect()
    }

    #[test]
    fn takes_the_same_paths_whatever_the_chunks() {
        // Keys 0..100 pushed in chunks of 7 and of 30: the same tails.
        for size in [7, 30, 100] {
            let mut q = PathQueue::default();
            let all: Vec<u64> = (0..100).collect();
            for c in all.chunks(size) {
                q.push_chunk(c.iter().map(|&k| path(k)).collect());
            }
            q.push_chunk(Vec::new());
            assert_eq!(q.len(), 100);
            let mut out = Vec::new();
            q.take_last(45, &mut out);
            assert_eq!(
                keys(&out),
                (55..100).collect::<Vec<_>>(),
                "chunks of {size}"
            );
            assert_eq!(q.len(), 55);
            out.clear();
            q.take_last(1000, &mut out);
            assert_eq!(keys(&out), (0..55).collect::<Vec<_>>());
            assert!(q.is_empty());
            out.clear();
            q.take_last(3, &mut out);
            assert!(out.is_empty());
        }
    }
}
