//! `--target-error` E → the flux-error metric's per-cell threshold τ (docs/design.md, "The flux-error metric").
//!
//! τ bounds what merging a cell's children may add to the 64²-filtered caustic map, relative to the cell's flux.
//! That bound is conservative by one to three orders of magnitude, and by how much depends on the scene, so τ
//! itself is a poor knob. E is what a user asks for: the rel-L1 at 64² that merging may add to max-level's image
//! at the same `--level`. The table below maps one to the other. It was measured with
//! `tools/calibrate-target-error` (docs/bench/llvmpipe-llvm-15-0-6-256-bits/calibration_target_error.md): for
//! each τ of a sweep, the largest added rel-L1 over the calibration runs (sphere, bunny and tilted cube under exact and two-interface
//! transport at level 3 with check level 2 and level 4 with the default check level 3; at level 5 the three
//! scenes under two-interface and the sphere and the bunny under exact transport), made non-decreasing in τ and
//! rounded up to three significant digits. E maps to the largest τ of the sweep whose error stayed within E on
//! every run: a staircase, not an interpolation, because the added error can jump between two τ of the sweep
//! (the tilted cube's flat faces converge all at once). Below the first node τ is [`TAU_MIN`], the smallest τ measured, and E is not
//! guaranteed there: under two-interface transport a cell whose four children all miss is dropped whatever τ,
//! which alone added 0.056% on the bunny at level 5. Above the last node τ stays at [`TAU_MAX`].

/// (E, τ): the added rel-L1 at 64² that τ reached at most over the calibration runs. Both columns strictly
/// increase; the last τ is [`TAU_MAX`].
pub const TARGET_ERROR_TABLE: [(f32, f32); 12] = [
    (0.000562, 0.003),
    (0.00057, 0.01),
    (0.000812, 0.02),
    (0.00369, 0.03),
    (0.00371, 0.04),
    (0.0041, 0.07),
    (0.00459, 0.1),
    (0.00662, 0.15),
    (0.0104, 0.2),
    (0.0158, 0.3),
    (0.0241, 0.5),
    (0.0485, 1.0),
];

/// The smallest τ the calibration measured: τ for every E below the first node.
pub const TAU_MIN: f32 = 0.001;

/// The largest τ the calibration measured, and the largest `--tau` accepted.
pub const TAU_MAX: f32 = 1.0;

/// τ for a target error E: the τ of the last node whose E is at most `e`, [`TAU_MIN`] below the first node.
/// Non-decreasing in E, at most [`TAU_MAX`].
pub fn tau_for_target_error(e: f32) -> f32 {
    TARGET_ERROR_TABLE.iter().rev().find(|&&(en, _)| en <= e).map_or(TAU_MIN, |&(_, t)| t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_table_is_strictly_increasing_and_ends_at_tau_max() {
        for w in TARGET_ERROR_TABLE.windows(2) {
            assert!(w[0].0 < w[1].0 && w[0].1 < w[1].1, "{w:?}");
        }
        assert_eq!(TARGET_ERROR_TABLE[TARGET_ERROR_TABLE.len() - 1].1, TAU_MAX);
        assert!(TARGET_ERROR_TABLE.iter().all(|&(e, t)| e > 0.0 && e <= 1.0 && t > 0.0));
    }

    #[test]
    fn tau_is_a_monotone_staircase_through_the_nodes() {
        for w in TARGET_ERROR_TABLE.windows(2) {
            let ((ea, ta), (eb, _)) = (w[0], w[1]);
            assert_eq!(tau_for_target_error(ea), ta);
            assert_eq!(tau_for_target_error(0.5 * (ea + eb)), ta);
        }
        let mut last = 0.0;
        for i in 0..=600 {
            let e = 10f32.powf(-6.0 + i as f32 / 100.0);
            let t = tau_for_target_error(e);
            assert!(t >= last && t > 0.0 && t <= TAU_MAX, "E {e}: tau {t} after {last}");
            last = t;
        }
        assert_eq!(tau_for_target_error(1.0), TAU_MAX);
        assert_eq!(tau_for_target_error(TARGET_ERROR_TABLE[0].0 * 0.99), TAU_MIN);
        assert!(TAU_MIN < TARGET_ERROR_TABLE[0].1);
        // The default and the values the tests and docs use.
        assert_eq!(tau_for_target_error(crate::settings::DEFAULT_TARGET_ERROR), 0.02);
        assert_eq!(tau_for_target_error(0.005), 0.1);
        assert_eq!(tau_for_target_error(0.0158), 0.3);
    }
}
