//! The integration tests, one module per subject, in one binary: one link
//! of the library and its dependencies instead of one per file, and one
//! process whose tests run on every core. A file directly in `tests/` would
//! be a binary of its own; `layering::every_test_file_is_a_module_of_this_binary`
//! fails when one appears.

mod common;
mod corpus;

mod bad_input;
mod bad_input_corpus;
mod baseline;
mod car;
mod cli;
mod declared;
mod declared_plan;
mod determinism;
mod diff_drive;
mod dilf;
mod dilf_random;
mod dilf_stall;
mod dilf_transport;
mod disk_pipeline;
mod doc_snippets;
mod external_law;
mod file_plan;
mod fit;
mod init;
mod install;
mod junit;
mod layering;
mod log_roundtrip;
mod log_unit;
mod margin;
mod margin_caps;
mod metrics;
mod obstacles;
mod own_plan_examples;
mod paper;
mod parallel;
mod perturbation_matrix;
mod properties;
mod published_robots;
mod reference;
mod report;
mod rerun_layout;
mod robot_examples;
mod ros_bags;
mod rover;
mod space_robot;
mod sphere;
mod sweep;
mod thread_cpu;
mod urdf_names;
mod urdf_warnings;
mod ux;
mod verdict;
mod xacro_packages;
