//! A rosbag2 recording on disk: its directory with `metadata.yaml`, or one `.mcap` file.

use std::fs::File;
use std::io::Read;
use std::path::{Path, PathBuf};

use crate::error::{Error, Location, Result};

/// The MCAP magic that starts (and ends) every MCAP file.
pub const MAGIC: &[u8; 8] = b"\x89MCAP0\r\n";

/// The MCAP files of a recording, in recording order.
#[derive(Clone, Debug)]
pub struct BagFiles {
    /// The directory or file the user named.
    pub path: PathBuf,
    /// The `.mcap` files.
    pub files: Vec<PathBuf>,
}

/// True when `path` is a rosbag2 recording: a directory with `metadata.yaml`, or a file that
/// starts with the MCAP magic (`\x89MCAP0\r\n`). Unreadable paths are not bags.
pub fn is_bag(path: &Path) -> Result<bool> {
    if path.is_dir() {
        return Ok(path.join("metadata.yaml").is_file());
    }
    let Ok(mut file) = File::open(path) else {
        return Ok(false);
    };
    let mut head = [0u8; 8];
    let mut got = 0;
    while got < head.len() {
        match file.read(&mut head[got..]) {
            Ok(0) => break,
            Ok(n) => got += n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(Error::io(path, Location::File, e)),
        }
    }
    Ok(got == head.len() && &head == MAGIC)
}

impl BagFiles {
    /// Resolves a bag directory (through its `metadata.yaml`) or an `.mcap` file.
    pub fn resolve(path: &Path) -> Result<Self> {
        if !path.is_dir() {
            if !is_bag(path)? {
                return Err(Error::UnknownFormat {
                    path: path.to_path_buf(),
                    reason: "not an MCAP file (it does not start with the MCAP magic)".into(),
                });
            }
            return Ok(Self {
                path: path.to_path_buf(),
                files: vec![path.to_path_buf()],
            });
        }
        let yaml_path = path.join("metadata.yaml");
        let text = std::fs::read_to_string(&yaml_path)
            .map_err(|e| Error::io(&yaml_path, Location::File, e))?;
        let meta = Metadata::parse(&text);
        let bad = |reason: String| Error::UnknownFormat {
            path: yaml_path.clone(),
            reason,
        };
        match meta.storage_identifier.as_deref() {
            Some("mcap") => {}
            Some(other) => {
                return Err(bad(format!(
                    "storage_identifier is {other:?}: only rosbag2 recordings with MCAP \
                     storage are read (convert with `ros2 bag convert`)"
                )));
            }
            None => return Err(bad("no storage_identifier".into())),
        }
        if meta
            .compression_mode
            .as_deref()
            .is_some_and(|m| m.eq_ignore_ascii_case("file"))
        {
            return Err(bad(
                "file-level compression (compression_mode FILE) is not supported; \
                 record with MCAP chunk compression instead"
                    .into(),
            ));
        }
        if meta.relative_file_paths.is_empty() {
            return Err(bad("relative_file_paths lists no files".into()));
        }
        let files = meta
            .relative_file_paths
            .iter()
            .map(|f| path.join(f))
            .collect();
        Ok(Self {
            path: path.to_path_buf(),
            files,
        })
    }

    /// Total size of the files in bytes.
    pub fn size_bytes(&self) -> u64 {
        self.files
            .iter()
            .filter_map(|f| std::fs::metadata(f).ok())
            .map(|m| m.len())
            .sum()
    }
}

/// The few fields of a rosbag2 `metadata.yaml` the reader needs.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Metadata {
    /// `storage_identifier` (`mcap`, `sqlite3`).
    pub storage_identifier: Option<String>,
    /// `compression_mode` (`""`, `FILE`, `MESSAGE`).
    pub compression_mode: Option<String>,
    /// `relative_file_paths`.
    pub relative_file_paths: Vec<String>,
}

fn unquote(v: &str) -> String {
    let v = v.trim();
    let inner = v
        .strip_prefix('"')
        .and_then(|s| s.strip_suffix('"'))
        .or_else(|| v.strip_prefix('\'').and_then(|s| s.strip_suffix('\'')));
    inner.unwrap_or(v).to_string()
}

impl Metadata {
    /// Reads the fields from the YAML text: `key: value` lines at any depth and the block list
    /// (`- item` lines) or flow list (`[a, b]`) under `relative_file_paths`.
    pub fn parse(text: &str) -> Self {
        let mut out = Self::default();
        let mut list_indent: Option<usize> = None;
        for line in text.lines() {
            let content = line.trim_start();
            if content.is_empty() || content.starts_with('#') {
                continue;
            }
            let indent = line.len() - content.len();
            if let Some(key_indent) = list_indent {
                if let Some(item) = content.strip_prefix('-')
                    && indent >= key_indent
                {
                    out.relative_file_paths.push(unquote(item));
                    continue;
                }
                list_indent = None;
            }
            let Some((key, value)) = content.split_once(':') else {
                continue;
            };
            let value = value.trim();
            match key.trim() {
                "storage_identifier" => out.storage_identifier = Some(unquote(value)),
                "compression_mode" => out.compression_mode = Some(unquote(value)),
                "relative_file_paths" => {
                    if let Some(flow) = value.strip_prefix('[').and_then(|v| v.strip_suffix(']')) {
                        out.relative_file_paths
                            .extend(flow.split(',').map(unquote).filter(|s| !s.is_empty()));
                    } else {
                        list_indent = Some(indent);
                    }
                }
                _ => {}
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_rosbag2_metadata() {
        let text = "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: mcap\n  \
            duration:\n    nanoseconds: 10\n  relative_file_paths:\n    - run_0.mcap\n    - \
            \"run_1.mcap\"\n  topics_with_message_count:\n    - topic_metadata:\n        name: \
            /scan\n  compression_format: \"\"\n  compression_mode: \"\"\n";
        let m = Metadata::parse(text);
        assert_eq!(m.storage_identifier.as_deref(), Some("mcap"));
        assert_eq!(m.relative_file_paths, vec!["run_0.mcap", "run_1.mcap"]);
        assert_eq!(m.compression_mode.as_deref(), Some(""));
        let flow =
            Metadata::parse("storage_identifier: sqlite3\nrelative_file_paths: [a.db3, 'b.db3']\n");
        assert_eq!(flow.relative_file_paths, vec!["a.db3", "b.db3"]);
        // rosbag2 also writes the list at the key's own indentation.
        let same = Metadata::parse("relative_file_paths:\n- x.mcap\nfiles:\n- path: x.mcap\n");
        assert_eq!(same.relative_file_paths, vec!["x.mcap"]);
    }
}
