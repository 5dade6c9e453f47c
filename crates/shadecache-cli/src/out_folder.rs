//! The folder a command writes its results to (`--out`).
//!
//! Three promises, each a defect a user met before it was kept:
//! - **Checked first.** The folder is made (or found) and written to
//!   before anything is measured, so that a typo or a read-only disk costs
//!   a second, not a sweep of minutes. Every message names the path.
//! - **One run's files.** A report never shows a previous run's maps or
//!   `choice/`. The files a run wrote are listed in the folder
//!   ([`MANIFEST`]), and the next run into it removes those, and only
//!   those, before it writes. A folder holding anything else (a user's
//!   files, a report of a shadecache too old to list its files) is
//!   refused unless `--overwrite` asks to write among them.
//! - **All or nothing.** A command that fails removes what it wrote, and
//!   the folder if it made it; the previous run's files are removed only
//!   once the new run has its results, so a failed run leaves the folder
//!   as it found it.
//!
//! Written here rather than with a crate: `tempfile`'s persisted folders
//! and `fs_extra` give atomic writes of one file or a copy of a tree, not
//! a record of which entries of a shared folder belong to whom.

use std::cell::RefCell;
use std::collections::BTreeSet;
use std::ffi::OsString;
use std::path::{Component, Path, PathBuf};

use shadecache::diagnostic::{Diagnostic, Error};

/// The list of what the last run wrote into the folder: one entry of the
/// folder per line.
pub const MANIFEST: &str = ".shadecache-out";

/// A checked output folder (see the module).
pub struct OutFolder {
    path: PathBuf,
    /// The outermost folder this run made, removed whole if it fails.
    made: Option<PathBuf>,
    /// The entries the previous run wrote (from [`MANIFEST`]).
    previous: Vec<OsString>,
    /// The folder's entries once the previous run's were removed: what
    /// was there before this run wrote anything. `None` until [`clear`].
    before: RefCell<Option<BTreeSet<OsString>>>,
}

fn fail(message: String) -> Error {
    Error::plain(Diagnostic::error(message))
}

/// The folder's entries by name.
fn entries(path: &Path) -> Result<BTreeSet<OsString>, Error> {
    std::fs::read_dir(path)
        .and_then(|dir| dir.map(|e| e.map(|e| e.file_name())).collect())
        .map_err(|err| fail(format!("cannot read `{}`: {err}", path.display())))
}

/// Removes `path` whatever it is; a folder with what it holds (a link is
/// removed, not followed). Already gone is fine.
fn remove(path: &Path) -> std::io::Result<()> {
    let result = match std::fs::symlink_metadata(path) {
        Ok(meta) if meta.is_dir() => std::fs::remove_dir_all(path),
        Ok(_) => std::fs::remove_file(path),
        Err(err) => Err(err),
    };
    match result {
        Err(err) if err.kind() == std::io::ErrorKind::NotFound => Ok(()),
        other => other,
    }
}

impl OutFolder {
    /// Makes or finds `path` and checks that it can be written, before
    /// anything is measured; refuses a folder holding files no shadecache
    /// run listed, unless `overwrite`.
    pub fn check(path: &Path, overwrite: bool) -> Result<OutFolder, Error> {
        let shown = path.display();
        if path.exists() && !path.is_dir() {
            return Err(fail(format!(
                "`{shown}` is a file: --out names the folder the results are written to"
            )));
        }
        // The outermost ancestor that does not exist yet is what this run
        // makes.
        let made = path
            .ancestors()
            .take_while(|a| !a.as_os_str().is_empty() && !a.exists())
            .last()
            .map(Path::to_path_buf);
        std::fs::create_dir_all(path)
            .map_err(|err| fail(format!("cannot create `{shown}`: {err}")))?;
        let folder = OutFolder {
            path: path.to_path_buf(),
            made,
            previous: Vec::new(),
            before: RefCell::new(None),
        };
        let probe = path.join(".shadecache-probe");
        if let Err(err) = std::fs::write(&probe, b"").and_then(|()| std::fs::remove_file(&probe)) {
            folder.abandon();
            return Err(fail(format!("cannot write into `{shown}`: {err}")));
        }
        let previous = match std::fs::read_to_string(path.join(MANIFEST)) {
            Ok(text) => text
                .lines()
                .filter(|line| !line.is_empty())
                .map(|line| match Path::new(line).components().collect::<Vec<_>>()[..] {
                    [Component::Normal(name)] => Ok(name.to_os_string()),
                    _ => Err(fail(format!(
                        "`{}` names `{line}`, which is not an entry of the folder: remove the file if it was edited by hand",
                        path.join(MANIFEST).display()
                    ))),
                })
                .collect::<Result<Vec<_>, _>>()?,
            Err(_) => Vec::new(),
        };
        let others: Vec<String> = entries(path)?
            .into_iter()
            .filter(|name| name != MANIFEST && !previous.contains(name))
            .map(|name| name.to_string_lossy().into_owned())
            .collect();
        if !others.is_empty() && !overwrite {
            let shown_names = others
                .iter()
                .take(4)
                .map(|n| format!("`{n}`"))
                .collect::<Vec<_>>();
            // The folder was there (it holds files): nothing to undo.
            return Err(fail(format!(
                "`{shown}` holds files a previous shadecache run did not list as its own ({}{}): name a new or empty folder, or pass --overwrite to write among them",
                shown_names.join(", "),
                if others.len() > 4 { ", …" } else { "" }
            )));
        }
        Ok(OutFolder { previous, ..folder })
    }

    /// Removes the previous run's files, once, when this run is about to
    /// write its own.
    pub fn clear(&self) -> Result<(), Error> {
        if self.before.borrow().is_some() {
            return Ok(());
        }
        for name in &self.previous {
            let old = self.path.join(name);
            remove(&old).map_err(|err| {
                fail(format!(
                    "cannot remove `{}`, a previous run's: {err}",
                    old.display()
                ))
            })?;
        }
        remove(&self.path.join(MANIFEST)).map_err(|err| {
            fail(format!(
                "cannot remove `{}`: {err}",
                self.path.join(MANIFEST).display()
            ))
        })?;
        *self.before.borrow_mut() = Some(entries(&self.path)?);
        Ok(())
    }

    /// What this run wrote: the entries that were not there when it
    /// cleared the folder.
    fn written(&self) -> Result<Vec<OsString>, Error> {
        let before = self.before.borrow().clone().unwrap_or_default();
        Ok(entries(&self.path)?
            .into_iter()
            .filter(|name| !before.contains(name))
            .collect())
    }

    /// Lists what this run wrote, for the next run to clear.
    pub fn finish(self) -> Result<(), Error> {
        self.clear()?;
        let mut list = String::new();
        for name in self.written()? {
            list.push_str(&name.to_string_lossy());
            list.push('\n');
        }
        let manifest = self.path.join(MANIFEST);
        std::fs::write(&manifest, list)
            .map_err(|err| fail(format!("cannot write `{}`: {err}", manifest.display())))
    }

    /// Removes what this run wrote, and the folder if it made it: a failed
    /// command leaves nothing.
    pub fn abandon(self) {
        if let Some(made) = &self.made {
            let _ = remove(made);
            return;
        }
        if self.before.borrow().is_some() {
            for name in self.written().unwrap_or_default() {
                let _ = remove(&self.path.join(name));
            }
        }
    }

    /// Runs `body`, then lists what it wrote; if it fails, removes it.
    pub fn run<T>(self, body: impl FnOnce(&OutFolder) -> Result<T, Error>) -> Result<T, Error> {
        match body(&self) {
            Ok(value) => self.finish().map(|()| value),
            Err(err) => {
                self.abandon();
                Err(err)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A second run into a folder removes the first run's files and only
    /// those; a folder with other files is refused unless overwritten; a
    /// failed run leaves the folder as it was, and removes a folder it
    /// made.
    #[test]
    fn a_reused_out_folder_shows_one_run() {
        let temp = tempfile::tempdir().unwrap();
        let out = temp.path().join("a/b");
        let first = OutFolder::check(&out, false).unwrap();
        first.clear().unwrap();
        std::fs::create_dir(out.join("maps")).unwrap();
        std::fs::write(out.join("maps/old.png"), b"").unwrap();
        std::fs::write(out.join("report.json"), b"1").unwrap();
        first.finish().unwrap();

        let second = OutFolder::check(&out, false).unwrap();
        second
            .run(|folder| {
                folder.clear()?;
                assert!(!out.join("maps").exists());
                std::fs::write(out.join("report.json"), b"2").unwrap();
                Ok(())
            })
            .unwrap();
        assert_eq!(std::fs::read(out.join("report.json")).unwrap(), b"2");

        // A failed run: the folder as it was.
        let third = OutFolder::check(&out, false).unwrap();
        let err = third.run(|folder| {
            folder.clear()?;
            std::fs::write(out.join("half.json"), b"").unwrap();
            Err::<(), _>(fail("measured nothing".into()))
        });
        assert!(err.is_err());
        assert!(!out.join("half.json").exists());

        // Someone else's file.
        std::fs::write(out.join("notes.txt"), b"mine").unwrap();
        let err = OutFolder::check(&out, false).err().unwrap().render();
        assert!(
            err.contains("`notes.txt`") && err.contains("--overwrite"),
            "{err}"
        );
        let kept = OutFolder::check(&out, true).unwrap();
        kept.run(|folder| folder.clear()).unwrap();
        assert!(out.join("notes.txt").exists());

        // A failed first run into a folder it made leaves no folder.
        let fresh = temp.path().join("c/d");
        let made = OutFolder::check(&fresh, false).unwrap();
        let _ = made.run(|_| Err::<(), _>(fail("no".into())));
        assert!(!temp.path().join("c").exists());

        // A file where the folder should be.
        let file = temp.path().join("file");
        std::fs::write(&file, b"").unwrap();
        let err = OutFolder::check(&file.join("sub"), false)
            .err()
            .unwrap()
            .render();
        assert!(
            err.contains(&file.join("sub").display().to_string()),
            "{err}"
        );
        let err = OutFolder::check(&file, false).err().unwrap().render();
        assert!(err.contains("is a file"), "{err}");
    }
}
