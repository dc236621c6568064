//! The linear engine's closed-form plate trajectory as the rupture models' [`PlatePath`]
//! (position along the piece and its proven bounds over a horizon).

use super::propagator::Trajectory;
use crate::engine::exact::rupture::path::PlatePath;

impl PlatePath for Trajectory {
    #[inline(always)]
    fn position(&self, s: f64) -> f64 {
        self.at(s).0
    }
    #[inline(always)]
    fn bounds(&self, h: f64) -> (f64, f64) {
        Trajectory::bounds(self, h)
    }
}
