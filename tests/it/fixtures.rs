//! The project's own fixtures are written by the project's own code: regenerating them with the
//! simulator's defaults gives the committed bytes (`trajdrift simulate fixtures/sim_ground/mission.mcap
//! --truth fixtures/sim_ground/truth.json --force`).

use std::io::Cursor;
use std::path::PathBuf;

use trajdrift::simulate::writer::{truth_json, write_mcap};
use trajdrift::simulate::{default_route, simulate, MissionConfig};

#[test]
fn sim_ground_is_reproducible() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fixtures/sim_ground");
    let mission = simulate(&MissionConfig::default(), &default_route());
    let mut out = Cursor::new(Vec::new());
    write_mcap(&mut out, &mission, 0).unwrap();
    let committed = std::fs::read(dir.join("mission.mcap")).unwrap();
    assert!(
        committed.len() < 1 << 20,
        "the fixture must stay well under 1 MB"
    );
    assert!(
        out.get_ref() == &committed,
        "fixtures/sim_ground/mission.mcap differs from the simulator's output"
    );
    let truth = serde_json::to_string_pretty(&truth_json(&mission)).unwrap() + "\n";
    assert_eq!(
        std::fs::read_to_string(dir.join("truth.json")).unwrap(),
        truth
    );
}
