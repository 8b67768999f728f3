//! Scene files: a [`SceneDesc`] written as RON.
//!
//! ```
//! use cloth3d::scenes::{file, Scene};
//!
//! let text = r#"(
//!     name: "tablecloth on a capsule",
//!     cloth: (
//!         cols: 16, rows: 16,
//!         placement: Horizontal(center: (0.0, 0.6, 0.0)),
//!         material: Preset("denim"),
//!     ),
//!     obstacles: [
//!         (shape: Capsule(half_height: 0.3, radius: 0.15), rotation: (1.5708, 0.0, 0.0)),
//!     ],
//!     frames: 30,
//! )"#;
//! let desc = file::from_ron(text)?;
//! let mut scene = Scene::from_desc(desc)?;
//! let metrics = cloth3d::scenes::run(&mut scene, 30)?;
//! assert!(metrics.finite && metrics.max_penetration < 0.002);
//!
//! // A mistake is reported with its line and field.
//! let err = file::from_ron(&text.replace("cols: 16", "cols: 1")).unwrap_err();
//! assert!(err.to_string().starts_with("line 4"), "{err}");
//! assert!(err.to_string().contains("cloth.cols"), "{err}");
//! # Ok::<(), cloth3d::SceneError>(())
//! ```

use std::path::Path;

use ron::ser::PrettyConfig;

use super::desc::SceneDesc;
use super::error::SceneError;

/// Reads a scene from RON text. Errors carry the line, column and field path.
pub fn from_ron(text: &str) -> Result<SceneDesc, SceneError> {
    let mut de = ron::Deserializer::from_str(text).map_err(|e| spanned(e, String::new()))?;
    let desc = match serde_path_to_error::deserialize::<_, SceneDesc>(&mut de) {
        Ok(desc) => desc,
        Err(e) => {
            let field = field_path(e.path());
            let inner = e.into_inner();
            return Err(spanned(de.span_error(inner), field));
        }
    };
    de.end()
        .map_err(|e| spanned(de.span_error(e), String::new()))?;
    Ok(desc)
}

/// Writes a scene as pretty RON text that [`from_ron`] reads back to the same description.
pub fn to_ron(desc: &SceneDesc) -> Result<String, SceneError> {
    let config = PrettyConfig::new()
        .struct_names(false)
        .depth_limit(6)
        .separate_tuple_members(false);
    let mut text = ron::ser::to_string_pretty(desc, config).map_err(|e| SceneError::File {
        path: String::new(),
        line: 0,
        column: 0,
        field: String::new(),
        message: e.to_string(),
    })?;
    text.push('\n');
    Ok(text)
}

/// Reads a scene file. Errors name the file, line, column and field.
pub fn load(path: &Path) -> Result<SceneDesc, SceneError> {
    let mut desc = from_ron(&read(path)?).map_err(|e| in_file(e, path))?;
    resolve_meshes(&mut desc, path);
    Ok(desc)
}

/// Makes the meshes' paths, relative to the scene file at `path`, usable
/// from here.
fn resolve_meshes(desc: &mut SceneDesc, path: &Path) {
    let dir = path.parent().unwrap_or(Path::new(""));
    for cloth in std::iter::once(&mut desc.cloth).chain(&mut desc.cloths) {
        if let Some(mesh) = &mut cloth.mesh {
            if Path::new(mesh.as_str()).is_relative() {
                *mesh = dir.join(&*mesh).display().to_string();
            }
        }
    }
}

/// Reads a scene file and hands its description to `build`; every error,
/// the file's or `build`'s, that names a field of the description names the
/// file and the field's line too.
pub fn load_with<T>(
    path: &Path,
    build: impl FnOnce(SceneDesc) -> Result<T, SceneError>,
) -> Result<T, SceneError> {
    let text = read(path)?;
    let mut desc = from_ron(&text).map_err(|e| in_file(e, path))?;
    resolve_meshes(&mut desc, path);
    build(desc).map_err(|e| in_file(locate(e, &text), path))
}

fn read(path: &Path) -> Result<String, SceneError> {
    std::fs::read_to_string(path).map_err(|e| SceneError::Io {
        path: path.display().to_string(),
        message: e.to_string(),
    })
}

/// Names `path` in a scene-file error.
fn in_file(err: SceneError, path: &Path) -> SceneError {
    match err {
        SceneError::File {
            line,
            column,
            field,
            message,
            ..
        } => SceneError::File {
            path: path.display().to_string(),
            line,
            column,
            field,
            message,
        },
        other => other,
    }
}

/// Places an error found while building a parsed scene (which names its
/// field but has no line) at the line of that field in `text`.
pub fn locate(err: SceneError, text: &str) -> SceneError {
    match err {
        SceneError::File {
            path,
            line: 0,
            field,
            message,
            ..
        } if !field.is_empty() => {
            let (line, column) = find_field(text, &field).unwrap_or((0, 0));
            SceneError::File {
                path,
                line,
                column,
                field,
                message,
            }
        }
        other => other,
    }
}

/// The line and column of `field` (a path like `cloth.pins.cells`) in `text`,
/// found by looking for each name in turn followed by `:`.
fn find_field(text: &str, field: &str) -> Option<(usize, usize)> {
    let mut from = 0;
    for part in field.split('.') {
        let name = part.split('[').next().unwrap_or(part);
        let mut search = from;
        loop {
            let at = search + text.get(search..)?.find(name)?;
            let after = text.get(at + name.len()..)?.trim_start();
            let before_ok = at == 0
                || !text[..at]
                    .chars()
                    .next_back()
                    .is_some_and(|c| c.is_alphanumeric() || c == '_');
            if before_ok && after.starts_with(':') {
                from = at;
                break;
            }
            search = at + name.len();
        }
    }
    let line = text[..from].matches('\n').count() + 1;
    let column = from - text[..from].rfind('\n').map(|i| i + 1).unwrap_or(0) + 1;
    Some((line, column))
}

fn spanned(e: ron::error::SpannedError, field: String) -> SceneError {
    SceneError::File {
        path: String::new(),
        line: e.span.start.line,
        column: e.span.start.col,
        field,
        message: e.code.to_string(),
    }
}

/// `cloth.pins.cells[2]` from serde_path_to_error's path (`.` when empty).
fn field_path(path: &serde_path_to_error::Path) -> String {
    // A segment serde could not name is shown as `?`: leave it out.
    let text = path.to_string();
    let text = text.trim_end_matches(".?").trim_end_matches('?');
    if text == "." {
        String::new()
    } else {
        text.to_string()
    }
}
