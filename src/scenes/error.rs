//! The error of building a scene: a cloth error, or a scene file's mistake
//! with its place, or a file that could not be read or written.

use thiserror::Error;

use crate::error::ClothError;

/// Everything that can go wrong when building a scene or reading its file.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum SceneError {
    /// Building or stepping the cloth failed.
    #[error(transparent)]
    Cloth(#[from] ClothError),
    /// A scene description is wrong: where, which field, and why.
    #[error(
        "{}line {line}, column {column}{}: {message}",
        path_prefix(path),
        field_suffix(field)
    )]
    File {
        /// The file (empty when the scene was read from text or built in code).
        path: String,
        /// Line of the error, counted from 1 (0 when it has no place in a text).
        line: usize,
        /// Column of the error, counted from 1.
        column: usize,
        /// Path of the field that is wrong, for example `cloth.material.stretch.stiffness`
        /// (empty when the error is in the syntax itself).
        field: String,
        /// What is wrong.
        message: String,
    },
    /// A file could not be read or written.
    #[error("{path}: {message}")]
    Io {
        /// The file.
        path: String,
        /// The system's message.
        message: String,
    },
}

impl SceneError {
    /// A mistake in the description's `field`, not yet placed in a text.
    pub(crate) fn field(field: impl Into<String>, err: impl std::fmt::Display) -> SceneError {
        SceneError::File {
            path: String::new(),
            line: 0,
            column: 0,
            field: field.into(),
            message: err.to_string(),
        }
    }
}

fn path_prefix(path: &str) -> String {
    if path.is_empty() {
        String::new()
    } else {
        format!("{path}: ")
    }
}

fn field_suffix(field: &str) -> String {
    if field.is_empty() {
        String::new()
    } else {
        format!(", field `{field}`")
    }
}
