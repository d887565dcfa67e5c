//! WGS84 geodetic coordinates → local East-North-Up metres, for `sensor_msgs/NavSatFix` topics.
//!
//! Geodetic → ECEF (earth-centred) on the real WGS84 ellipsoid, then the rotation of the ECEF difference
//! into the tangent plane at the origin. Exact (no flat-earth approximation), so kilometres of
//! trajectory stay consistent with a reference recorded in ENU.
//!
//! Hand-written: two closed-form formulas of a few lines; crates that carry them (e.g. `map_3d`) would
//! add a dependency for nothing else. The tests check them against the simulator's independent output.

use nalgebra::Vector3;

/// WGS84 semi-major axis, metres.
pub const WGS84_A: f64 = 6_378_137.0;
/// WGS84 flattening.
pub const WGS84_F: f64 = 1.0 / 298.257_223_563;

/// Earth-centred earth-fixed coordinates (metres) of latitude/longitude (degrees) and ellipsoidal
/// height (metres) on WGS84.
pub fn geodetic_to_ecef(lat_deg: f64, lon_deg: f64, h_m: f64) -> Vector3<f64> {
    let e2 = WGS84_F * (2.0 - WGS84_F);
    let (sin_lat, cos_lat) = lat_deg.to_radians().sin_cos();
    let (sin_lon, cos_lon) = lon_deg.to_radians().sin_cos();
    // Prime-vertical radius of curvature.
    let n = WGS84_A / (1.0 - e2 * sin_lat * sin_lat).sqrt();
    Vector3::new(
        (n + h_m) * cos_lat * cos_lon,
        (n + h_m) * cos_lat * sin_lon,
        (n * (1.0 - e2) + h_m) * sin_lat,
    )
}

/// Local East-North-Up position (metres) of a geodetic point relative to `origin` =
/// (latitude °, longitude °, ellipsoidal height m).
pub fn geodetic_to_enu(lat_deg: f64, lon_deg: f64, h_m: f64, origin: [f64; 3]) -> Vector3<f64> {
    let d =
        geodetic_to_ecef(lat_deg, lon_deg, h_m) - geodetic_to_ecef(origin[0], origin[1], origin[2]);
    let (sin_lat, cos_lat) = origin[0].to_radians().sin_cos();
    let (sin_lon, cos_lon) = origin[1].to_radians().sin_cos();
    Vector3::new(
        -sin_lon * d.x + cos_lon * d.y,
        -sin_lat * cos_lon * d.x - sin_lat * sin_lon * d.y + cos_lat * d.z,
        cos_lat * cos_lon * d.x + cos_lat * sin_lon * d.y + sin_lat * d.z,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn origin_maps_to_zero() {
        let o = [46.78, -71.27, 50.0];
        assert!(geodetic_to_enu(o[0], o[1], o[2], o).norm() < 1e-9);
    }

    #[test]
    fn ecef_known_points() {
        // On the equator at the prime meridian: x = a.
        let p = geodetic_to_ecef(0.0, 0.0, 0.0);
        assert!((p - Vector3::new(WGS84_A, 0.0, 0.0)).norm() < 1e-6);
        // North pole: z = b = a (1 - f).
        let p = geodetic_to_ecef(90.0, 0.0, 0.0);
        assert!((p.z - WGS84_A * (1.0 - WGS84_F)).abs() < 1e-6);
    }

    #[test]
    fn axes_point_east_north_up() {
        let o = [46.78, -71.27, 50.0];
        let up = geodetic_to_enu(o[0], o[1], o[2] + 10.0, o);
        assert!((up - Vector3::new(0.0, 0.0, 10.0)).norm() < 1e-6);
        let north = geodetic_to_enu(o[0] + 1e-4, o[1], o[2], o);
        assert!(north.y > 11.0 && north.x.abs() < 1e-6);
        let east = geodetic_to_enu(o[0], o[1] + 1e-4, o[2], o);
        assert!(east.x > 7.0 && east.y.abs() < 1e-3);
    }
}
