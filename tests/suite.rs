//! The integration tests: one module per issue, built as one test binary (one link and one
//! optimised build of the code they share, instead of one per file).
//!
//! `cargo test --release --test suite` runs them all; a module or a test by name:
//! `cargo test --release --test suite issue_7_scenarios::` or `… suite golden`.

mod common;

mod issue_13_reconstruction;
mod issue_14_fuzz;
mod issue_15_first_hour;
mod issue_16_viewer;
mod issue_17_fast_laser;
mod issue_17_fleet;
mod issue_17_glide;
mod issue_17_polling;
mod issue_18_honest_matches;
mod issue_19_live;
mod issue_19_maps;
mod issue_19_recording;
mod issue_19_replay;
mod issue_20_navigation;
mod issue_2_bad_input;
mod issue_2_collision;
mod issue_2_contract;
mod issue_2_determinism;
mod issue_2_firmware;
mod issue_2_laser;
mod issue_2_odometry;
mod issue_2_twin_run;
mod issue_3_laser_realism;
mod issue_3_pan_tilt;
mod issue_3_sonar;
mod issue_4_localisation;
mod issue_5_protocol;
mod issue_5_serial;
mod issue_5_serve;
mod issue_6_montecarlo;
mod issue_7_scenarios;
