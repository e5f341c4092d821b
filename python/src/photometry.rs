//! `luxtally.Photometry`: an IES LM-63 or EULUMDAT file read by the engine's reader
//! (the one `[[lights]] type = "luminaire"` uses), its candela table as arrays.

use crate::errors::IntoPy;
use numpy::{IntoPyArray, PyArrayDyn, PyReadonlyArrayDyn};
use pyo3::prelude::*;
use std::path::PathBuf;

/// A luminaire's photometric file.
#[pyclass(module = "luxtally", frozen)]
pub struct Photometry {
    p: luxtally::photometry::Photometry,
}

#[pymethods]
impl Photometry {
    /// Reads `path` (`.ies` as LM-63, `.ldt` as EULUMDAT), as `luxtally photometry`.
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf) -> PyResult<Photometry> {
        let p = py.detach(|| luxtally::photometry::load(&path)).py_err()?;
        Ok(Photometry { p })
    }

    /// The luminaire's flux (lm), integrated exactly over the candela table.
    #[getter]
    fn flux_lm(&self) -> f64 {
        self.p.flux_lm()
    }

    /// The largest intensity in the table (cd).
    #[getter]
    fn peak_cd(&self) -> f64 {
        self.p.peak_cd()
    }

    /// The lamps' rated flux (lm); None for absolute photometry.
    #[getter]
    fn lamp_flux_lm(&self) -> Option<f64> {
        self.p.lamp_flux_lm
    }

    /// Luminaire flux over lamp flux; None for absolute photometry.
    #[getter]
    fn light_output_ratio(&self) -> Option<f64> {
        self.p.light_output_ratio()
    }

    /// Intensity (cd) at C-plane angle `c_deg` and polar angle `gamma_deg`.
    fn intensity_cd(&self, c_deg: f64, gamma_deg: f64) -> f64 {
        self.p.intensity_cd(c_deg, gamma_deg)
    }

    /// Intensities (cd) at arrays of C-plane and polar angles (degrees, same shape).
    fn intensities_cd<'py>(
        &self,
        py: Python<'py>,
        c_deg: PyReadonlyArrayDyn<'py, f64>,
        gamma_deg: PyReadonlyArrayDyn<'py, f64>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let (c, g) = (c_deg.as_array(), gamma_deg.as_array());
        if c.shape() != g.shape() {
            return Err(pyo3::exceptions::PyValueError::new_err(
                "c_deg and gamma_deg must have the same shape",
            ));
        }
        let cd = numpy::ndarray::Zip::from(&c)
            .and(&g)
            .map_collect(|&c, &g| self.p.intensity_cd(c, g));
        Ok(cd.into_pyarray(py))
    }

    /// The lines `luxtally photometry` prints about the file.
    fn summary_lines(&self) -> Vec<String> {
        self.p.summary_lines()
    }

    /// Writes the polar diagram (PNG) to `path`, as `luxtally photometry --out`.
    fn polar_png(&self, path: PathBuf) -> PyResult<()> {
        let png = luxtally::photometry::polar::polar_diagram_png(&self.p).py_err()?;
        luxtally::output::write_atomic(&path, |w| std::io::Write::write_all(w, &png)).py_err()
    }

    fn __repr__(&self) -> String {
        format!("Photometry({:?}: {:.1} lm)", self.p.file, self.p.flux_lm())
    }
}
