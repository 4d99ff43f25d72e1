//! Writing a finished figure or page (`plot -o`, `report -o`): an existing non-empty file is
//! never replaced unless `force` is given (CONTRACT.md's `--force`), and the bytes go to a
//! temporary file beside the target that is renamed over it, so a failed write never leaves
//! half a page where a good one was.

use std::io::Write;
use std::path::Path;

use crate::error::UsageError;

/// Writes `bytes` to `path`; refuses an existing non-empty file unless `force` (exit status 2).
pub fn write_page(path: &Path, bytes: &[u8], force: bool) -> anyhow::Result<()> {
    if !force {
        if let Ok(m) = std::fs::metadata(path) {
            if m.len() > 0 || !m.is_file() {
                return Err(anyhow::Error::new(UsageError::Option(format!(
                    "{} exists; give --force to overwrite it",
                    path.display()
                ))));
            }
        }
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => std::path::PathBuf::from("."),
    };
    let name = path
        .file_name()
        .map(|f| f.to_string_lossy().to_string())
        .unwrap_or_else(|| "out".into());
    let tmp = dir.join(format!(".{name}.{}.tmp", std::process::id()));
    let result = (|| -> std::io::Result<()> {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        anyhow::bail!("cannot write {}: {e}", path.display());
    }
    Ok(())
}
