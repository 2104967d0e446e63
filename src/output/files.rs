//! Output written whole or not at all: the files of a run go into a temporary folder inside
//! the output folder and are moved into place only when the run succeeds.

use std::path::{Path, PathBuf};

/// Writes `files` into `out` whole or not at all: `write` fills a temporary folder inside
/// `out`, whose files are moved into place only when it succeeds, so a failed run leaves
/// earlier results untouched; folders created for `out` are removed again on failure.
pub fn write_whole<T, E>(
    out: &Path,
    files: &[&str],
    write_err: impl Fn(PathBuf, std::io::Error) -> E,
    write: impl FnOnce(&Path) -> Result<T, E>,
) -> Result<T, E> {
    let created = missing_folders(out);
    let outcome = (|| {
        std::fs::create_dir_all(out).map_err(|e| write_err(out.to_path_buf(), e))?;
        remove_stale_partials(out);
        let tmp = out.join(format!(".viscobar-partial-{}", std::process::id()));
        // Left by an earlier process with this id (`remove_stale_partials` spares it).
        let _ = std::fs::remove_dir_all(&tmp);
        std::fs::create_dir_all(&tmp).map_err(|e| write_err(tmp.clone(), e))?;
        let outcome = write(&tmp).and_then(|value| {
            for file in files {
                // A folder of files (ParaView's `vtu/`) replaces the one of an earlier run.
                if tmp.join(file).is_dir() && out.join(file).is_dir() {
                    std::fs::remove_dir_all(out.join(file))
                        .map_err(|e| write_err(out.join(file), e))?;
                }
                std::fs::rename(tmp.join(file), out.join(file))
                    .map_err(|e| write_err(out.join(file), e))?;
            }
            Ok(value)
        });
        let _ = std::fs::remove_dir_all(&tmp);
        outcome
    })();
    if outcome.is_err() {
        // Deepest first; `remove_dir` leaves a folder that is not empty.
        for folder in &created {
            let _ = std::fs::remove_dir(folder);
        }
    }
    outcome
}

/// `out` and those of its parents that do not exist yet, deepest first.
pub fn missing_folders(out: &Path) -> Vec<PathBuf> {
    out.ancestors()
        .filter(|p| !p.as_os_str().is_empty())
        .take_while(|p| !p.exists())
        .map(Path::to_path_buf)
        .collect()
}

/// Writes `bytes` to `path` whole or not at all: a temporary file in the same folder, then a
/// rename.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .map_or("out".into(), |n| n.to_string_lossy().into_owned());
    let tmp = dir.join(format!(".{name}.partial-{}", std::process::id()));
    let result = std::fs::write(&tmp, bytes).and_then(|()| std::fs::rename(&tmp, path));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Removes the temporary folders that interrupted runs (killed before they could clean up)
/// left in `out`, unless their process is still running.
fn remove_stale_partials(out: &Path) {
    let Ok(entries) = std::fs::read_dir(out) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        let Some(pid) = name.strip_prefix(".viscobar-partial-") else {
            continue;
        };
        if !Path::new("/proc").join(pid).exists() {
            let _ = std::fs::remove_dir_all(entry.path());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fresh(tag: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("viscobar-whole-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        dir
    }

    /// A folder left with this process's id (not removed as stale: the id is alive) is cleared
    /// and reused; the temporary folder is gone afterwards, whether the write succeeds or fails.
    #[test]
    fn write_whole_reuses_a_left_folder_and_removes_its_own() {
        let out = fresh("left");
        let tmp = out.join(format!(".viscobar-partial-{}", std::process::id()));
        std::fs::create_dir_all(tmp.join("sub")).unwrap();
        std::fs::write(tmp.join("a.csv"), "old").unwrap();
        let io = |path: PathBuf, e: std::io::Error| format!("{}: {e}", path.display());
        let ok = write_whole(&out, &["a.csv"], io, |dir| {
            assert!(!dir.join("sub").exists(), "the left folder is cleared");
            std::fs::write(dir.join("a.csv"), "new").map_err(|e| e.to_string())
        });
        assert_eq!(ok, Ok(()));
        assert_eq!(std::fs::read_to_string(out.join("a.csv")).unwrap(), "new");
        assert!(!tmp.exists());
        let failed: Result<(), String> = write_whole(&out, &["a.csv"], io, |dir| {
            std::fs::write(dir.join("a.csv"), "half").unwrap();
            Err("failed".to_string())
        });
        assert!(failed.is_err());
        assert_eq!(std::fs::read_to_string(out.join("a.csv")).unwrap(), "new");
        assert!(
            !tmp.exists(),
            "a failed write's folder, not empty, is removed too"
        );
        std::fs::remove_dir_all(&out).unwrap();
    }
}
