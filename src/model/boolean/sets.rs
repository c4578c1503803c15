//! Disjoint sets of the numbers `0..n` (union-find), each set named by its smallest
//! member, so that the names do not depend on the order of the joins.

/// A partition of `0..n` into sets.
pub(crate) struct Sets(Vec<u32>);

impl Sets {
    /// `n` sets of one member each.
    pub fn new(n: usize) -> Sets {
        Sets((0..n as u32).collect())
    }

    /// The name of the set holding `x` (paths are halved on the way).
    pub fn find(&mut self, mut x: u32) -> u32 {
        let p = &mut self.0;
        while p[x as usize] != x {
            p[x as usize] = p[p[x as usize] as usize];
            x = p[x as usize];
        }
        x
    }

    /// Joins the sets of `a` and `b`; whether they were apart.
    pub fn join(&mut self, a: u32, b: u32) -> bool {
        let (a, b) = (self.find(a), self.find(b));
        if a != b {
            self.0[a.max(b) as usize] = a.min(b);
        }
        a != b
    }
}
