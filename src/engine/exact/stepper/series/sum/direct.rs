//! Direct mode's store: the live junctions' offsets with stable handles (module doc of
//! [`super`], "Direct mode").

use serde::{Deserialize, Serialize};

use super::bins::NONE;
use super::graded::Grades;

/// Direct mode's junctions: their offsets `e_i = c_i - origin` (frame-independent, like the
/// bins' offsets) in a dense array, and stable handles through a handle -> position table
/// (swap-remove: O(1) `add` and `remove`), and their graded orders.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Direct {
    /// `e_i` of the live junctions, positions `0..n`.
    pub(super) e: Vec<f64>,
    /// The handle of the junction at each position.
    pub(super) handle: Vec<u32>,
    /// The position of each handle (`NONE`: free).
    pub(super) pos: Vec<u32>,
    /// Free handles.
    pub(super) free: Vec<u32>,
    /// The junctions' orders (derived from `law.l0` and `p`, not serialised).
    pub(super) grades: Grades,
}

/// Serialized form of [`Direct`] (the position table is rebuilt on reading).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct DirectWire {
    pub(super) e: Vec<f64>,
    pub(super) handle: Vec<u32>,
    pub(super) free: Vec<u32>,
}

impl Direct {
    /// No junctions, orders `grades`.
    pub(super) fn new(grades: Grades) -> Direct {
        Direct { e: Vec::new(), handle: Vec::new(), pos: Vec::new(), free: Vec::new(), grades }
    }

    /// The junctions read from `w` (the position table rebuilt), orders `grades`.
    pub(super) fn from_wire(w: DirectWire, grades: Grades) -> Direct {
        let len = w.handle.iter().chain(&w.free).map(|&h| h as usize + 1).max().unwrap_or(0);
        let mut pos = vec![NONE; len];
        for (i, &h) in w.handle.iter().enumerate() {
            pos[h as usize] = i as u32;
        }
        Direct { e: w.e, handle: w.handle, pos, free: w.free, grades }
    }

    /// Stores a junction with offset `e`; returns its handle. O(1).
    #[inline]
    pub(super) fn insert(&mut self, e: f64) -> u32 {
        let at = self.e.len() as u32;
        let h = match self.free.pop() {
            Some(h) => {
                self.pos[h as usize] = at;
                h
            }
            None => {
                self.pos.push(at);
                self.pos.len() as u32 - 1
            }
        };
        self.e.push(e);
        self.handle.push(h);
        h
    }

    /// Forgets the junction with handle `h`; returns its offset as stored. O(1).
    #[inline]
    pub(super) fn take(&mut self, h: u32) -> f64 {
        let at = self.pos.get(h as usize).copied().unwrap_or(NONE);
        assert!(at != NONE, "SeriesSum::remove: handle {h} has no junction");
        let at = at as usize;
        let e = self.e.swap_remove(at);
        self.handle.swap_remove(at);
        if let Some(&moved) = self.handle.get(at) {
            self.pos[moved as usize] = at as u32;
        }
        self.pos[h as usize] = NONE;
        self.free.push(h);
        e
    }
}
