//! The `sqlite3` storage of rosbag2: tables `topics(id, name, type, serialization_format, ...)` and
//! `messages(id, topic_id, timestamp, data)`, read with `rusqlite` (SQLite compiled in, nothing to
//! install). The database is opened read-only and `immutable`, so no journal or lock file is
//! created next to it (the folder may be read-only) and the file is never modified.

use std::collections::HashMap;
use std::path::Path;

use crate::error::{Error, Result};
use crate::sources::recording::{ChannelInfo, MessageRef, OnMessage};

/// Streams the messages of the `selected` channels (by topic name) of the database `path`, in
/// storage order. Rows are fetched one at a time: memory does not grow with the database.
pub fn for_each_message(
    path: &Path,
    channels: &[ChannelInfo],
    selected: &[bool],
    on_message: OnMessage<'_>,
) -> Result<()> {
    let bad = |e: rusqlite::Error| sqlite_error(path, e);
    let db = open_immutable(path)?;
    let route = routes(&db, channels, selected).map_err(bad)?;
    if route.is_empty() {
        return Ok(());
    }
    let ids: Vec<String> = route.keys().map(|id| id.to_string()).collect();
    let sql = format!(
        "SELECT topic_id, timestamp, data FROM messages WHERE topic_id IN ({})",
        ids.join(",")
    );
    let mut stmt = db.prepare(&sql).map_err(bad)?;
    let mut rows = stmt.query([]).map_err(bad)?;
    while let Some(row) = rows.next().map_err(bad)? {
        let topic_id: i64 = row.get(0).map_err(bad)?;
        let stamp: i64 = row.get(1).map_err(bad)?;
        let data = row
            .get_ref(2)
            .map_err(bad)?
            .as_blob()
            .map_err(|e| bad(e.into()))?;
        let Some(&i) = route.get(&topic_id) else {
            continue;
        };
        let c = &channels[i];
        let t = u64::try_from(stamp).unwrap_or(0);
        on_message(
            c,
            &MessageRef {
                channel_id: c.id,
                sequence: 0,
                log_time: t,
                publish_time: t,
                data,
            },
        )?;
    }
    Ok(())
}

/// A database error as the one-line error of `path`.
fn sqlite_error(path: &Path, e: rusqlite::Error) -> Error {
    Error::Rosbag2 {
        path: path.to_path_buf(),
        detail: format!("sqlite3: {e}; check the file with `ros2 bag info`"),
    }
}

/// Opens the database read-only and `immutable` (no journal, no lock file, nothing written).
fn open_immutable(path: &Path) -> Result<rusqlite::Connection> {
    // URI form so `immutable=1` applies; the characters URIs reserve are escaped.
    let escaped: String = path
        .to_string_lossy()
        .chars()
        .map(|c| match c {
            '%' => "%25".to_string(),
            '?' => "%3f".to_string(),
            '#' => "%23".to_string(),
            c => c.to_string(),
        })
        .collect();
    rusqlite::Connection::open_with_flags(
        format!("file:{escaped}?immutable=1"),
        rusqlite::OpenFlags::SQLITE_OPEN_READ_ONLY | rusqlite::OpenFlags::SQLITE_OPEN_URI,
    )
    .map_err(|e| sqlite_error(path, e))
}

/// Database topic id → index into `channels`, for the selected channels only (matched by topic
/// name: the database's ids are its own).
fn routes(
    db: &rusqlite::Connection,
    channels: &[ChannelInfo],
    selected: &[bool],
) -> rusqlite::Result<HashMap<i64, usize>> {
    let by_name: HashMap<&str, usize> = channels
        .iter()
        .enumerate()
        .map(|(i, c)| (c.topic.as_str(), i))
        .collect();
    let mut route: HashMap<i64, usize> = HashMap::new();
    let mut stmt = db.prepare("SELECT id, name FROM topics")?;
    let rows = stmt.query_map([], |r| Ok((r.get::<_, i64>(0)?, r.get::<_, String>(1)?)))?;
    for row in rows {
        let (id, name) = row?;
        if let Some(&i) = by_name.get(name.as_str()).filter(|&&i| selected[i]) {
            route.insert(id, i);
        }
    }
    Ok(route)
}
