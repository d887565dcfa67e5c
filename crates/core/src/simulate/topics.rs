//! GrandTour's topic names for the sensors the simulator writes: what the multi-clock mission's
//! sources are called ([`crate::simulate::sources`]) and what the bag writer writes them under
//! ([`crate::simulate::grandtour`], which re-exports them).

/// The INS solution (the `grandtour` preset's reference).
pub const INS_TOPIC: &str = "/boxi/inertial_explorer/tc/odometry";
/// The total station's prism position (the `grandtour-prism` preset's reference).
pub const PRISM_TOPIC: &str = "/boxi/ap20/prism_position";
/// DLIO lidar-inertial odometry.
pub const DLIO_TOPIC: &str = "/boxi/dlio/lidar_map_odometry";
/// The ANYmal state estimator.
pub const STATE_ESTIMATOR_TOPIC: &str = "/anymal/state_estimator/odometry";
/// open3d_slam lidar odometry (in the multi-clock layout only).
pub const OPEN3D_SLAM_TOPIC: &str = "/open3d_slam/odometry";
