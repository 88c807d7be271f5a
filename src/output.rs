//! Output files: checked before any work, written atomically.
//!
//! Unguarded, `fit data.csv -o data.csv` replaced the measurements with
//! model JSON, an unwritable output failed only after the fit, and an
//! interrupted write left a half-written file. So every command
//!
//! 1. calls [`check_outputs`] before it starts: no output may be the same
//!    file as an input or as another output (the same path once resolved, or
//!    a hard link to it), and every output must be writable — its folder
//!    exists and takes a new file, and it is neither a folder nor read-only;
//! 2. writes each file with [`write_atomic`]: into a temporary file in the
//!    same folder, renamed over the target only once complete, so a reader
//!    sees the old file or the new one, never a part.

use std::io::{self, Write};
use std::path::{Path, PathBuf};

use crate::{Error, Result};

/// Files no output may replace for the rest of the process, beyond each
/// command's own inputs: `run`'s config file, read once but not an input
/// of the steps it runs.
static PROTECTED: std::sync::Mutex<Vec<PathBuf>> = std::sync::Mutex::new(Vec::new());

/// Refuse, from now on, any output that is the file `path`
/// ([`check_outputs`] and [`write_atomic`]).
pub fn protect(path: &Path) {
    let mut p = PROTECTED.lock().unwrap_or_else(|e| e.into_inner());
    p.push(resolve(path));
}

/// The protected file `path` is, if any.
fn protected(path: &Path) -> Option<PathBuf> {
    let r = resolve(path);
    let p = PROTECTED.lock().unwrap_or_else(|e| e.into_inner());
    p.iter().find(|q| **q == r || same_file(q, path)).cloned()
}

/// The error for an output that would replace the protected file `p`.
fn refuse_protected(out: &Path, p: &Path) -> Error {
    Error::InvalidParameter(format!(
        "output {} is {}, which this run reads: refusing to overwrite it",
        out.display(),
        p.display()
    ))
}

/// Write `path` atomically: `fill` writes the whole content into a
/// temporary file in the same folder, which then replaces `path` by a
/// rename. On any failure `path` is left as it was and the temporary file
/// is removed. `-` is refused: it means standard output everywhere else.
/// New files get the usual permissions (`0666` less the umask).
pub fn write_atomic(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> io::Result<()>,
) -> Result<()> {
    let io_err = |e| Error::io(path, e);
    if is_stdout(path) {
        return Err(Error::InvalidParameter(
            "'-' would be a file named '-': standard output takes only the --json reports; give a file name".into(),
        ));
    }
    if let Some(p) = protected(path) {
        return Err(refuse_protected(path, &p));
    }
    let mut tmp = temp_beside(path).map_err(io_err)?;
    {
        let mut w = io::BufWriter::new(tmp.as_file_mut());
        fill(&mut w).map_err(io_err)?;
        w.flush().map_err(io_err)?;
    }
    tmp.as_file().sync_all().map_err(io_err)?;
    tmp.persist(path).map_err(|e| io_err(e.error))?;
    Ok(())
}

/// [`write_atomic`] of a whole text.
pub fn write_text(path: &Path, text: &str) -> Result<()> {
    write_atomic(path, |w| w.write_all(text.as_bytes()))
}

/// `value` as pretty JSON with a final newline, the text of every JSON
/// report file (`context` names it in an error).
pub fn json_text(value: &impl serde::Serialize, context: &str) -> Result<String> {
    let text = serde_json::to_string_pretty(value).map_err(|e| Error::Json {
        context: context.into(),
        source: e,
    })?;
    Ok(text + "\n")
}

/// A new temporary file in `path`'s folder, named after it.
fn temp_beside(path: &Path) -> io::Result<tempfile::NamedTempFile> {
    let name = path
        .file_name()
        .map_or_else(|| "output".into(), |n| n.to_string_lossy().into_owned());
    let prefix = format!(".{name}.");
    let mut b = tempfile::Builder::new();
    b.prefix(&prefix).suffix(".tmp");
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        b.permissions(std::fs::Permissions::from_mode(0o666));
    }
    b.tempfile_in(folder(path))
}

/// Whether an output path is `-`: standard output.
pub fn is_stdout(path: &Path) -> bool {
    path == Path::new("-")
}

/// Create the folder a file is written in, and its parents, if missing.
pub fn create_folder_of(path: &Path) -> Result<()> {
    let dir = folder(path);
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))
}

/// The folder a file is written in (`.` for a bare file name).
fn folder(path: &Path) -> &Path {
    path.parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."))
}

/// Refuse, before any work, an output that is the same file as an input or
/// as another output — the same path once resolved (symbolic links, `./`,
/// `..`) or the same file under another name (a hard link: same device and
/// inode) — or that cannot be written: its folder is missing or does not
/// take a new file, or it is a folder or a read-only file. `-` (standard
/// output) is always fine.
pub fn check_outputs(inputs: &[&Path], outputs: &[&Path]) -> Result<()> {
    for (k, out) in outputs.iter().enumerate() {
        if is_stdout(out) {
            continue;
        }
        let r = resolve(out);
        if let Some(p) = protected(out) {
            return Err(refuse_protected(out, &p));
        }
        for inp in inputs {
            if r == resolve(inp) || same_file(out, inp) {
                return Err(Error::InvalidParameter(format!(
                    "output {} is the input {}: refusing to overwrite it",
                    out.display(),
                    inp.display()
                )));
            }
        }
        for other in &outputs[..k] {
            if r == resolve(other) || same_file(out, other) {
                return Err(Error::InvalidParameter(format!(
                    "outputs {} and {} are the same file: one would overwrite the other",
                    other.display(),
                    out.display()
                )));
            }
        }
        check_writable(out)?;
    }
    Ok(())
}

/// [`check_outputs`] of the paths given, `None` being an optional file
/// (a command's option) that was not.
pub fn check_given(inputs: &[Option<&Path>], outputs: &[Option<&Path>]) -> Result<()> {
    fn given<'a>(v: &[Option<&'a Path>]) -> Vec<&'a Path> {
        v.iter().flatten().copied().collect()
    }
    check_outputs(&given(inputs), &given(outputs))
}

/// An output file can be written: see [`check_outputs`].
pub fn check_writable(path: &Path) -> Result<()> {
    let refuse = |why: String| {
        Err(Error::Input {
            source_name: path.display().to_string(),
            message: format!("cannot be written: {why}"),
        })
    };
    if let Ok(meta) = std::fs::metadata(path) {
        if meta.is_dir() {
            return refuse("it is a folder; give a file name".into());
        }
        if meta.permissions().readonly() {
            return refuse("the file is read-only".into());
        }
    }
    let dir = folder(path);
    if !dir.is_dir() {
        return refuse(format!("the folder {} does not exist", dir.display()));
    }
    match temp_beside(path) {
        Ok(_) => Ok(()), // removed on drop
        Err(e) => refuse(format!(
            "the folder {} does not take a new file ({e})",
            dir.display()
        )),
    }
}

/// `p` with symbolic links, `.` and `..` resolved; for a file still to be
/// written, its folder resolved and its name appended.
fn resolve(p: &Path) -> PathBuf {
    if let Ok(c) = std::fs::canonicalize(p) {
        return c;
    }
    match (std::fs::canonicalize(folder(p)), p.file_name()) {
        (Ok(d), Some(name)) => d.join(name),
        _ => p.to_path_buf(),
    }
}

#[cfg(unix)]
fn same_file(a: &Path, b: &Path) -> bool {
    use std::os::unix::fs::MetadataExt;
    match (std::fs::metadata(a), std::fs::metadata(b)) {
        (Ok(x), Ok(y)) => x.dev() == y.dev() && x.ino() == y.ino(),
        _ => false,
    }
}

#[cfg(not(unix))]
fn same_file(_: &Path, _: &Path) -> bool {
    false
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_failed_write_leaves_the_old_file_and_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("out.json");
        std::fs::write(&p, "old").unwrap();
        let r = write_atomic(&p, |w| {
            w.write_all(b"half")?;
            Err(io::Error::other("disk full"))
        });
        assert!(r.is_err());
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "old");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
        write_text(&p, "new").unwrap();
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "new");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn unwritable_outputs_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        assert!(check_writable(dir.path()).is_err());
        assert!(check_writable(&dir.path().join("no/such/folder.json")).is_err());
        let ro = dir.path().join("ro.json");
        std::fs::write(&ro, "x").unwrap();
        let mut perm = std::fs::metadata(&ro).unwrap().permissions();
        perm.set_readonly(true);
        std::fs::set_permissions(&ro, perm).unwrap();
        assert!(check_writable(&ro).is_err());
        assert!(check_writable(&dir.path().join("fine.json")).is_ok());
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }
}
