//! Streaming MCAP source (placeholder, being written).
