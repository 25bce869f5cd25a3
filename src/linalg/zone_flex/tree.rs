//! The supernodal elimination tree of a faer factor as the zone pass walks it
//! ([`Tree`]): each supernode's parent and children, a postorder in which every subtree
//! is one range, the rows under each subtree, and the zone's columns sorted so that a
//! subtree's zone rows are one range of columns.

use faer::sparse::linalg::cholesky::supernodal::SupernodalLltRef;

use super::NONE;

/// The supernodal elimination tree: each supernode's end, parent and
/// children, a postorder of it (faer numbers supernodes children first, but a
/// subtree's supernodes need not be consecutive) and each subtree's rows.
pub(super) struct Tree {
    pub(super) end: Vec<usize>,
    pub(super) parent: Vec<usize>,
    pub(super) children: Vec<Vec<usize>>,
    /// The supernodes in postorder; the subtree of `s` is `post[first[s]..=at[s]]`.
    pub(super) post: Vec<usize>,
    pub(super) at: Vec<usize>,
    pub(super) first: Vec<usize>,
    /// Rows of the factor in each subtree.
    pub(super) rows: Vec<usize>,
}

impl Tree {
    pub(super) fn new(llt: SupernodalLltRef<'_, usize, f64>) -> Option<Self> {
        let sym = llt.symbolic();
        let ns = sym.n_supernodes();
        let begin = sym.supernode_begin()[..ns].to_vec();
        let end = sym.supernode_end()[..ns].to_vec();
        let owner = |r: usize| end.partition_point(|&e| e <= r);
        let mut parent = Vec::with_capacity(ns);
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); ns];
        let mut rows: Vec<usize> = (0..ns).map(|s| end[s] - begin[s]).collect();
        for s in 0..ns {
            let p = llt
                .supernode(s)
                .pattern()
                .first()
                .map_or(NONE, |&r| owner(r));
            // the traversals visit children before parents
            if p != NONE && p <= s {
                return None;
            }
            if p != NONE {
                children[p].push(s);
                rows[p] += rows[s];
            }
            parent.push(p);
        }
        // postorder by an explicit stack (a tree can be thousands deep)
        let (mut post, mut at, mut first) = (Vec::with_capacity(ns), vec![0; ns], vec![0; ns]);
        let mut stack: Vec<(usize, usize)> = Vec::new();
        for root in (0..ns).filter(|&s| parent[s] == NONE) {
            stack.push((root, 0));
            first[root] = post.len();
            while let Some(&mut (s, ref mut next)) = stack.last_mut() {
                if let Some(&c) = children[s].get(*next) {
                    *next += 1;
                    first[c] = post.len();
                    stack.push((c, 0));
                } else {
                    at[s] = post.len();
                    post.push(s);
                    stack.pop();
                }
            }
        }
        Some(Tree {
            end,
            parent,
            children,
            post,
            at,
            first,
            rows,
        })
    }

    /// The supernode holding factor row `r`.
    pub(super) fn owner(&self, r: usize) -> usize {
        self.end.partition_point(|&e| e <= r)
    }

    /// The zone's columns `(factor row, zone index)` sorted by the postorder of their
    /// supernodes (then by row), and for each supernode the range of them whose row
    /// lies in its subtree and the start of those in itself (the range's tail).
    #[allow(clippy::type_complexity)]
    pub(super) fn sorted_columns(
        &self,
        rows: impl Iterator<Item = usize>,
    ) -> (Vec<(usize, usize)>, Vec<(usize, usize)>, Vec<usize>) {
        let ns = self.end.len();
        let mut cols: Vec<(usize, usize)> = rows.enumerate().map(|(c, p)| (p, c)).collect();
        cols.sort_unstable_by_key(|&(p, _)| (self.at[self.owner(p)], p));
        let mut own = vec![0usize; ns];
        for &(p, _) in &cols {
            own[self.owner(p)] += 1;
        }
        // a subtree's columns are those of its postorder range
        let mut before = vec![0usize; ns + 1];
        for (i, &s) in self.post.iter().enumerate() {
            before[i + 1] = before[i] + own[s];
        }
        let ranges = (0..ns)
            .map(|s| (before[self.first[s]], before[self.at[s] + 1]))
            .collect();
        let own_lo = (0..ns).map(|s| before[self.at[s]]).collect();
        (cols, ranges, own_lo)
    }
}
