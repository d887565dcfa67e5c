//! The message definitions of a rosbag2 recording, by type name, so `--annotate` can write its channels
//! with their schemas. metadata.yaml names types only: the definitions are in the storage (the
//! sqlite3 `message_definitions` table written since ROS 2 Iron, the MCAP files' schema records), and
//! for the types trajdrift reads we know them ourselves ([`crate::decode::ros2_schemas`]).

use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::Arc;

use super::Storage;

/// Type name → `ros2msg` definition, from the storage when it holds them, else ours; a type found in
/// neither is absent (its channel is written schemaless-by-name with an empty definition).
pub fn definitions(storage: Storage, files: &[PathBuf]) -> HashMap<String, Arc<[u8]>> {
    let mut out: HashMap<String, Arc<[u8]>> = HashMap::new();
    for f in files {
        match storage {
            Storage::Sqlite3 => sqlite_definitions(f, &mut out),
            Storage::Mcap => {
                if let Some(s) = crate::sources::mcap::summary::read_mcap_summary(f) {
                    for schema in s.schemas.values() {
                        out.entry(schema.name.clone())
                            .or_insert_with(|| schema.data.as_ref().into());
                    }
                }
            }
        }
    }
    for t in crate::decode::supported_types() {
        if let Some(text) = crate::decode::ros2_schemas::schema_text(t) {
            out.entry(t.to_string())
                .or_insert_with(|| text.as_bytes().into());
        }
    }
    out
}

/// Reads the `message_definitions` table when there is one (older databases have none: not an error).
fn sqlite_definitions(path: &std::path::Path, out: &mut HashMap<String, Arc<[u8]>>) {
    let Ok(db) =
        rusqlite::Connection::open_with_flags(path, rusqlite::OpenFlags::SQLITE_OPEN_READ_ONLY)
    else {
        return;
    };
    let Ok(mut stmt) =
        db.prepare("SELECT topic_type, encoded_message_definition FROM message_definitions")
    else {
        return;
    };
    let Ok(rows) = stmt.query_map([], |r| Ok((r.get::<_, String>(0)?, r.get::<_, String>(1)?)))
    else {
        return;
    };
    for (name, text) in rows.flatten() {
        if !text.is_empty() {
            out.entry(name).or_insert_with(|| text.as_bytes().into());
        }
    }
}
