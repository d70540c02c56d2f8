//! An integrator other than the harness's fixed-step RK4, to check ideal
//! runs against: adaptive Dormand–Prince 5(4), relative tolerance 1e-12.

/// One adaptive Dormand–Prince 5(4) run of y' = f(t, y) from `t0` to `t1`.
pub fn dopri(f: &dyn Fn(f64, &[f64]) -> Vec<f64>, mut y: Vec<f64>, t0: f64, t1: f64) -> Vec<f64> {
    const C: [f64; 7] = [0.0, 0.2, 0.3, 0.8, 8.0 / 9.0, 1.0, 1.0];
    const A: [[f64; 6]; 7] = [
        [0.0; 6],
        [0.2, 0.0, 0.0, 0.0, 0.0, 0.0],
        [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0],
        [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0],
        [
            19372.0 / 6561.0,
            -25360.0 / 2187.0,
            64448.0 / 6561.0,
            -212.0 / 729.0,
            0.0,
            0.0,
        ],
        [
            9017.0 / 3168.0,
            -355.0 / 33.0,
            46732.0 / 5247.0,
            49.0 / 176.0,
            -5103.0 / 18656.0,
            0.0,
        ],
        [
            35.0 / 384.0,
            0.0,
            500.0 / 1113.0,
            125.0 / 192.0,
            -2187.0 / 6784.0,
            11.0 / 84.0,
        ],
    ];
    const B5: [f64; 7] = [
        35.0 / 384.0,
        0.0,
        500.0 / 1113.0,
        125.0 / 192.0,
        -2187.0 / 6784.0,
        11.0 / 84.0,
        0.0,
    ];
    const B4: [f64; 7] = [
        5179.0 / 57600.0,
        0.0,
        7571.0 / 16695.0,
        393.0 / 640.0,
        -92097.0 / 339200.0,
        187.0 / 2100.0,
        1.0 / 40.0,
    ];
    let tol = 1e-12;
    let (mut t, mut h) = (t0, ((t1 - t0) / 100.0).max(1e-9));
    let n = y.len();
    let mut steps = 0;
    while t < t1 {
        steps += 1;
        assert!(steps < 10_000_000, "Dormand–Prince does not advance");
        h = h.min(t1 - t);
        let mut k: Vec<Vec<f64>> = Vec::with_capacity(7);
        for s in 0..7 {
            let ys: Vec<f64> = (0..n)
                .map(|i| y[i] + h * (0..s).map(|j| A[s][j] * k[j][i]).sum::<f64>())
                .collect();
            k.push(f(t + C[s] * h, &ys));
        }
        let y5: Vec<f64> = (0..n)
            .map(|i| y[i] + h * (0..7).map(|s| B5[s] * k[s][i]).sum::<f64>())
            .collect();
        let err = (0..n)
            .map(|i| {
                let e = h * (0..7).map(|s| (B5[s] - B4[s]) * k[s][i]).sum::<f64>();
                e.abs() / (tol * (1.0 + y[i].abs().max(y5[i].abs())))
            })
            .fold(0.0, f64::max);
        if err <= 1.0 {
            t += h;
            y = y5;
        }
        h *= (0.9 * err.max(1e-10).powf(-0.2)).clamp(0.2, 5.0);
    }
    y
}
