//! Exact volumes on an integer grid: a region kept as disjoint boxes with integer
//! corners, from which boxes are subtracted. The volume is an integer count of grid
//! cells, computed without the kernel.

/// A box with integer corners, `lo < hi` on every axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct IBox {
    /// The low corner.
    pub lo: [i64; 3],
    /// The high corner.
    pub hi: [i64; 3],
}

impl IBox {
    /// The number of grid cells inside.
    pub fn volume(&self) -> i64 {
        (0..3).map(|k| self.hi[k] - self.lo[k]).product()
    }

    /// Whether the open interiors meet.
    pub fn overlaps(&self, other: &IBox) -> bool {
        (0..3).all(|k| self.lo[k] < other.hi[k] && other.lo[k] < self.hi[k])
    }
}

/// A region as disjoint boxes.
#[derive(Clone, Debug)]
pub struct BoxSet {
    boxes: Vec<IBox>,
}

impl BoxSet {
    /// The region of one box.
    pub fn new(start: IBox) -> BoxSet {
        BoxSet { boxes: vec![start] }
    }

    /// Removes `cut`: each box it overlaps is split into at most six boxes outside it.
    pub fn subtract(&mut self, cut: &IBox) {
        let mut out = Vec::with_capacity(self.boxes.len());
        for &b in &self.boxes {
            if !b.overlaps(cut) {
                out.push(b);
                continue;
            }
            let mut rest = b;
            for k in 0..3 {
                if rest.lo[k] < cut.lo[k] {
                    let mut piece = rest;
                    piece.hi[k] = cut.lo[k];
                    out.push(piece);
                    rest.lo[k] = cut.lo[k];
                }
                if rest.hi[k] > cut.hi[k] {
                    let mut piece = rest;
                    piece.lo[k] = cut.hi[k];
                    out.push(piece);
                    rest.hi[k] = cut.hi[k];
                }
            }
        }
        self.boxes = out;
    }

    /// The number of grid cells in the region.
    pub fn volume(&self) -> i64 {
        self.boxes.iter().map(IBox::volume).sum()
    }

    /// The number of boxes held.
    pub fn len(&self) -> usize {
        self.boxes.len()
    }

    /// Whether the region is empty.
    pub fn is_empty(&self) -> bool {
        self.boxes.is_empty()
    }
}
