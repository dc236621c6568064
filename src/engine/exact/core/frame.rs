//! Local coordinates of the exact engine, re-based during long runs so that positions and
//! times keep their digits: absolute time `t = epoch + tau`, absolute plate position
//! `X = x_ref + y`, and the lag behind the driver `X - V t = (y - V tau) + lag_ref` with
//! `lag_ref = x_ref - V epoch` carried separately (never recomputed from large numbers).

use serde::{Deserialize, Serialize};

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Frame {
    /// Absolute time of the local origin.
    pub epoch: f64,
    /// Absolute position of the local origin.
    pub x_ref: f64,
    /// `x_ref - V epoch`.
    pub lag_ref: f64,
    /// Driving velocity `V`.
    pub v: f64,
}

impl Frame {
    pub fn new(v: f64) -> Frame {
        Frame { epoch: 0.0, x_ref: 0.0, lag_ref: 0.0, v }
    }
    /// Absolute time of local time `tau`.
    #[inline]
    pub fn time(&self, tau: f64) -> f64 {
        self.epoch + tau
    }
    /// Local time of absolute time `t`.
    #[inline]
    pub fn local(&self, t: f64) -> f64 {
        t - self.epoch
    }
    /// Absolute position of local position `y`.
    #[inline]
    pub fn position(&self, y: f64) -> f64 {
        self.x_ref + y
    }
    /// Lag `X - V t` at local `(y, tau)`.
    #[inline]
    pub fn lag(&self, y: f64, tau: f64) -> f64 {
        (y - self.v * tau) + self.lag_ref
    }
    /// Moves the origin by `dtau` in time and `dy` in position.
    pub fn shift(&mut self, dtau: f64, dy: f64) {
        self.epoch += dtau;
        self.x_ref += dy;
        self.lag_ref += dy - self.v * dtau;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shifting_keeps_absolute_quantities() {
        let mut f = Frame::new(0.5);
        let (y, tau) = (1234.5, 2000.25);
        let (t, x, lag) = (f.time(tau), f.position(y), f.lag(y, tau));
        f.shift(tau, y);
        assert_eq!(f.time(0.0), t);
        assert_eq!(f.position(0.0), x);
        assert!((f.lag(0.0, 0.0) - lag).abs() < 1e-12);
    }
}
