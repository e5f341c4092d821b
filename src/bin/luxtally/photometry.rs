//! `luxtally photometry`: a photometric file's facts on stdout, its polar diagram as PNG.

use luxtally::{output, photometry, Result};
use std::io::Write;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct PhotometryArgs {
    pub file: PathBuf,
    /// The diagram's path (default: FILE's stem + `_polar.png` in the current directory).
    #[arg(long, value_name = "PNG")]
    pub out: Option<PathBuf>,
}

pub fn command(args: PhotometryArgs) -> Result<()> {
    let file = &args.file;
    let p = photometry::load(file)?;
    let out = args.out.unwrap_or_else(|| {
        let stem = file
            .file_stem()
            .map_or("luminaire".into(), |s| s.to_string_lossy());
        PathBuf::from(format!("{stem}_polar.png"))
    });
    let png = photometry::polar::polar_diagram_png(&p)?;
    output::write_atomic(&out, |w| w.write_all(&png))?;
    for line in p.summary_lines() {
        println!("{line}");
    }
    println!("polar diagram: {}", out.display());
    Ok(())
}
