//! The fast offset search changes how the answer is
//! computed, not the answer: on every shared mission, `eval` with all defaults gives the applied Δt
//! within 1 ms and the Drift Error RMSE within 1e-4 of what the direct search gave before it
//! (the table: trajdrift at f2e5065, `eval MISSION --reference /reference/position --estimate
//! /estimate/odom --json`, all defaults).
//!
//! Since `auto` refines its answer by the pose fit (a different estimator, on purpose), the search's
//! own answer is the report's `speed` entry (the method `auto` applied on every one of these
//! missions): on the constant clocks it is compared with the table; on the drifting and stepping
//! clocks the table held the clock model's headline, which the pose fit now gives. The Drift Error
//! is compared where the applied Δt stayed within 1 ms of the table's.

use crate::common;

use trajdrift::align::time_offset::OffsetMethod;
use trajdrift::evaluate;
use trajdrift::{EvalConfig, NamedInput};

/// Mission, applied Δt (s), DE RMSE at 5 m, from the direct search.
const BEFORE: [(&str, f64, f64); 7] = [
    ("clock_drift", -0.24644699550543664, 0.020112806215276398),
    ("clock_step", -0.099881422990232, 0.02018004729882896),
    ("gnss_outages", -0.3485449263776354, 0.020081688444432675),
    ("legged", 0.08022518275491504, 0.02024263863994685),
    ("legged_spins", -0.1466197685490537, 0.021348759927737916),
    ("lever_arm", 0.09963616482666536, 0.02015602921435496),
    ("straight", 0.2504683853035043, 0.020365379421789877),
];

#[test]
fn shared_missions_give_the_direct_searchs_answers() {
    let Some(shared) = common::shared() else {
        return;
    };
    for (name, dt, de) in BEFORE {
        let config = EvalConfig::new(
            Some(common::mission(&shared, name)),
            NamedInput::topic("/reference/position"),
            vec![NamedInput::topic("/estimate/odom")],
        );
        let report = evaluate(&config).unwrap();
        let e = &report.estimates[0];
        let searched = e
            .time_offset
            .methods
            .iter()
            .find(|m| m.method == OffsetMethod::Speed)
            .and_then(|m| m.offset_s)
            .unwrap_or(e.time_offset.applied_s);
        let (got_dt, got_de) = (searched, e.drift_error[0].rmse.unwrap());
        println!(
            "{name:<13} Δt {got_dt:+.6} s (before {dt:+.6}, {:+.4} ms)  DE {got_de:.6} (before {de:.6})",
            (got_dt - dt) * 1e3
        );
        if !name.starts_with("clock_") {
            assert!((got_dt - dt).abs() <= 1e-3, "{name}: Δt {got_dt} vs {dt}");
        }
        // The Drift Error moves with the applied Δt: compared where the pose fit left it within
        // 1 ms of the table's.
        if (e.time_offset.applied_s - dt).abs() <= 1e-3 {
            assert!((got_de - de).abs() <= 1e-4, "{name}: DE {got_de} vs {de}");
        }
    }
}
