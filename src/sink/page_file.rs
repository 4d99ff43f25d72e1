//! Writing a finished figure or page (`plot -o`, `report -o`): an existing non-empty file is
//! never replaced unless `force` is given (CONTRACT.md's `--force`), and the bytes go to a
//! temporary file beside the target that is renamed over it, so a failed write never leaves
//! half a page where a good one was. `-` is standard output.

use std::io::Write;
use std::path::Path;

use crate::error::UsageError;

/// Refuses an output path that cannot be a file: a directory, or one in a folder that does not
/// exist (a usage error naming `what`, the option, and the path). `-` (standard output) passes.
pub fn check_target(path: &Path, what: &str) -> Result<(), UsageError> {
    if path == Path::new("-") {
        return Ok(());
    }
    if path.is_dir() {
        return Err(UsageError::Option(format!(
            "{what} {}: is a directory; give a file name",
            path.display()
        )));
    }
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        if !dir.is_dir() {
            return Err(UsageError::Option(format!(
                "{what} {}: the folder {} does not exist; create it first",
                path.display(),
                dir.display()
            )));
        }
    }
    Ok(())
}

/// Writes `bytes` to `path` (`-`: standard output); refuses an existing non-empty file unless
/// `force`, a directory, or a missing folder (exit status 2).
pub fn write_page(path: &Path, bytes: &[u8], force: bool) -> anyhow::Result<()> {
    check_target(path, "-o")?;
    if path == Path::new("-") {
        let mut out = std::io::stdout().lock();
        out.write_all(bytes)
            .and_then(|()| out.flush())
            .map_err(|e| anyhow::anyhow!("cannot write to standard output: {e}"))?;
        return Ok(());
    }
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
