//! The engine's errors as Python exceptions, with the CLI's one-line message (what
//! `luxtally` prints after `luxtally: `).

use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::PyErr;

create_exception!(
    luxtally,
    LuxtallyError,
    PyException,
    "An error of the engine: the same one-line message the CLI prints."
);
create_exception!(
    luxtally,
    SceneError,
    LuxtallyError,
    "Bad input (a scene, a file, an option): names the file and key at fault, as the CLI does."
);

/// The CLI's message for `e` (`luxtally: MESSAGE` on its stderr).
pub fn message(e: &luxtally::Error) -> String {
    luxtally::input::one_line(&e.to_string())
}

/// `e` as an exception: bad input and unreadable files are a `SceneError`, the rest a
/// `LuxtallyError`.
pub fn to_py(e: luxtally::Error) -> PyErr {
    let text = message(&e);
    match e {
        luxtally::Error::Input { .. } | luxtally::Error::Io { .. } => SceneError::new_err(text),
        _ => LuxtallyError::new_err(text),
    }
}

/// `Result` of the engine into `PyResult`.
pub trait IntoPy<T> {
    fn py_err(self) -> pyo3::PyResult<T>;
}

impl<T> IntoPy<T> for luxtally::Result<T> {
    fn py_err(self) -> pyo3::PyResult<T> {
        self.map_err(to_py)
    }
}
