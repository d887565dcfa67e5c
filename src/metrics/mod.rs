//! Metrics: Drift Error (the paper) and, later, the standard APE/RPE.
