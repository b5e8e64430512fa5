//! Finding the files an OBJ or MTL names (`mtllib`, `map_Kd`, …) as exporters write them: Windows
//! separators, absolute paths from the exporter's machine, a different letter case. A name that
//! does not resolve as written is looked for by its file name next to the naming file and one folder
//! below it, letter case ignored (as Blender's OBJ importer searches the folder it imports from).

use std::path::{Path, PathBuf};

/// Where a named file was found.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Located {
    /// The file to open: found, or (when nothing matched) the name as written, relative to `dir`.
    pub path: PathBuf,
    /// Set when the file was found elsewhere than written, for a warning.
    pub substituted: bool,
}

/// Resolves `written` (relative to `dir`, `\` read as `/`): as written if that file exists, else
/// the first file named like its last component (letter case ignored) in `dir` or a folder directly
/// inside `dir`. When nothing matches, the path as written (opening it gives the caller's error).
pub fn locate(dir: &Path, written: &str) -> Located {
    let name = written.trim().replace('\\', "/");
    let as_written = dir.join(&name);
    if as_written.is_file() {
        return Located { path: as_written, substituted: false };
    }
    let Some(file_name) = name.rsplit('/').next().filter(|f| !f.is_empty()) else {
        return Located { path: as_written, substituted: false };
    };
    let mut folders = vec![dir.to_path_buf()];
    if let Ok(entries) = std::fs::read_dir(dir) {
        let mut subfolders: Vec<PathBuf> = entries.flatten().map(|e| e.path()).filter(|p| p.is_dir()).collect();
        subfolders.sort();
        folders.extend(subfolders);
    }
    for folder in folders {
        if let Some(found) = find_ignoring_case(&folder, file_name) {
            return Located { path: found, substituted: true };
        }
    }
    Located { path: as_written, substituted: false }
}

/// The file in `folder` whose name equals `file_name`, exactly or else ignoring ASCII case (the
/// first in sorted order when several differ only by case).
fn find_ignoring_case(folder: &Path, file_name: &str) -> Option<PathBuf> {
    let exact = folder.join(file_name);
    if exact.is_file() {
        return Some(exact);
    }
    let mut matches: Vec<PathBuf> = std::fs::read_dir(folder)
        .ok()?
        .flatten()
        .filter(|e| e.file_name().to_str().is_some_and(|n| n.eq_ignore_ascii_case(file_name)))
        .map(|e| e.path())
        .filter(|p| p.is_file())
        .collect();
    matches.sort();
    matches.into_iter().next()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exporter_paths_fall_back_to_the_file_name_near_the_naming_file() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir(dir.path().join("textures")).unwrap();
        std::fs::write(dir.path().join("textures/Brick.PNG"), b"x").unwrap();
        std::fs::write(dir.path().join("wood.jpg"), b"x").unwrap();
        let found = |w: &str| locate(dir.path(), w);
        assert_eq!(found("wood.jpg"), Located { path: dir.path().join("wood.jpg"), substituted: false });
        assert_eq!(
            found("textures\\Brick.PNG"),
            Located { path: dir.path().join("textures/Brick.PNG"), substituted: false }
        );
        for written in ["C:\\Users\\bob\\proj\\brick.png", "/home/bob/proj/textures/brick.png", "brick.png"] {
            assert_eq!(found(written), Located { path: dir.path().join("textures/Brick.PNG"), substituted: true });
        }
        assert_eq!(found("D:\\maps\\wood.jpg").path, dir.path().join("wood.jpg"));
        assert_eq!(found("gone.png"), Located { path: dir.path().join("gone.png"), substituted: false });
    }
}
