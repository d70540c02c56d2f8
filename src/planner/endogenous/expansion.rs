//! The Legendre basis and one segment's control expansion (Eq. 15).

use crate::planner::endogenous::params::Order;

/// Legendre polynomials P_0..P_{p−1}(s) and their derivatives d/ds (p = vals.len()).
pub fn legendre(s: f64, vals: &mut [f64], ders: &mut [f64]) {
    let p = vals.len();
    if p == 0 {
        return;
    }
    vals[0] = 1.0;
    ders[0] = 0.0;
    if p == 1 {
        return;
    }
    vals[1] = s;
    ders[1] = 1.0;
    for k in 1..p - 1 {
        let kf = k as f64;
        vals[k + 1] = ((2.0 * kf + 1.0) * s * vals[k] - kf * vals[k - 1]) / (kf + 1.0);
        ders[k + 1] = ders[k - 1] + (2.0 * kf + 1.0) * vals[k];
    }
}

/// One segment's control: a Legendre series per input (Eq. 15).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ControlExpansion {
    /// Global start time, s.
    pub start: f64,
    /// Segment duration T, s.
    pub duration: f64,
    /// Number of Legendre terms per input.
    pub terms: Vec<usize>,
    /// Parameters λ, input after input.
    pub lambda: Vec<f64>,
}

impl ControlExpansion {
    fn offsets(terms: &[usize]) -> Vec<usize> {
        terms
            .iter()
            .scan(0, |acc, &p| {
                let o = *acc;
                *acc += p;
                Some(o)
            })
            .collect()
    }

    /// Row of P(t) (order Value) or dP/dt (Derivative) for input `input`:
    /// the coefficients c with u_input(t) (or u'_input) = c · λ.
    pub fn basis_row(
        terms: &[usize],
        duration: f64,
        local_t: f64,
        order: Order,
        input: usize,
    ) -> Vec<f64> {
        let s_total: usize = terms.iter().sum();
        let pmax = terms.iter().copied().max().unwrap_or(0);
        let (mut v, mut d) = (vec![0.0; pmax], vec![0.0; pmax]);
        legendre(2.0 * local_t / duration - 1.0, &mut v, &mut d);
        let off = Self::offsets(terms)[input];
        let mut row = vec![0.0; s_total];
        for k in 0..terms[input] {
            row[off + k] = match order {
                Order::Value => v[k],
                Order::Derivative => d[k] * 2.0 / duration,
            };
        }
        row
    }

    /// u(t) (order Value) or du/dt (Derivative) at global time t (not clamped).
    pub fn eval(&self, t: f64, order: Order) -> Vec<f64> {
        let pmax = self.terms.iter().copied().max().unwrap_or(0);
        // Stack buffers for the usual sizes: this runs at every RK4 stage of a replay.
        let (mut sv, mut sd) = ([0.0; 64], [0.0; 64]);
        let (mut hv, mut hd);
        let (v, d): (&mut [f64], &mut [f64]) = if pmax <= 64 {
            (&mut sv[..pmax], &mut sd[..pmax])
        } else {
            hv = vec![0.0; pmax];
            hd = vec![0.0; pmax];
            (&mut hv, &mut hd)
        };
        legendre(2.0 * (t - self.start) / self.duration - 1.0, v, d);
        let scale = 2.0 / self.duration;
        let mut off = 0;
        let mut out = Vec::with_capacity(self.terms.len());
        for &p in &self.terms {
            let lam = &self.lambda[off..off + p];
            let val: f64 = match order {
                Order::Value => lam.iter().zip(v.iter()).map(|(l, b)| l * b).sum(),
                Order::Derivative => {
                    scale * lam.iter().zip(d.iter()).map(|(l, b)| l * b).sum::<f64>()
                }
            };
            out.push(val);
            off += p;
        }
        out
    }
}
