//! `luxtally ugr-table`: a luminaire file's CIE 190 UGR table on stdout (the datasheet
//! layout, 1000 lm), as CSV and as a plot if asked.

use luxtally::stats::ugr_table::{self, Table, View, REFERENCE_FLUX_LM, REFLECTANCES};
use luxtally::{output, photometry, Error, Result};
use std::io::Write;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct UgrTableArgs {
    pub file: PathBuf,
    /// Spacing-to-height ratio of the luminaire array: 1 (CIE 190's standard) or 0.25
    /// (the catalogue habit).
    #[arg(long, default_value_t = 1.0)]
    pub shr: f64,
    /// Also write the table (1000 lm) as CSV here.
    #[arg(long, value_name = "PATH")]
    pub csv: Option<PathBuf>,
    /// Also plot UGR (70/50/20, 1000 lm) against the room length Y for each width X,
    /// crosswise and endwise, as PNG here.
    #[arg(long, value_name = "PNG")]
    pub plot: Option<PathBuf>,
}

pub fn command(args: UgrTableArgs) -> Result<()> {
    if args.shr != 1.0 && args.shr != 0.25 {
        return Err(Error::input(
            "--shr",
            format!("{} is not a CIE 190 spacing (expected 1 or 0.25)", args.shr),
        ));
    }
    let p = photometry::load(&args.file)?;
    let table = ugr_table::table(&p, args.shr, REFERENCE_FLUX_LM)?;
    let rated = ugr_table::rated_flux_lm(&p);
    if let Some(path) = &args.csv {
        let csv = csv_text(&table);
        output::write_atomic(path, |w| w.write_all(csv.as_bytes()))?;
    }
    if let Some(path) = &args.plot {
        let png = ugr_table::plot_png(&table)?;
        output::write_atomic(path, |w| w.write_all(&png))?;
    }
    for line in text_lines(&table, &p.file, rated) {
        println!("{line}");
    }
    for (what, path) in [("csv", &args.csv), ("plot", &args.plot)] {
        if let Some(path) = path {
            println!("{what}: {}", path.display());
        }
    }
    Ok(())
}

/// A value as the table prints it: one decimal, `-` where no luminaire counts. Values
/// below 10 are printed as they are (AGi32 prints them as 10).
fn cell(v: Option<f64>) -> String {
    v.map_or("-".into(), |v| format!("{v:.1}"))
}

/// The datasheet: rooms down, crosswise then endwise across, reflectances under each;
/// then the flux correction and the reference value.
fn text_lines(t: &Table, file: &str, rated_lm: f64) -> Vec<String> {
    let refl: Vec<String> = REFLECTANCES
        .iter()
        .map(|r| format!("{:>8}", r.label()))
        .collect();
    let refl = refl.join(" ");
    let mut lines = vec![
        format!("UGR table (CIE 190:2010) of {file}"),
        format!(
            "SHR {}, {REFERENCE_FLUX_LM:.0} lm lamp flux, H = {} m above the eye; \
             reflectances ceiling/walls/floor",
            t.shr,
            ugr_table::H_M
        ),
        format!("{:<10} {:<44}   {}", "room", "crosswise", "endwise"),
        format!("{:<10} {refl}   {refl}", "X    Y"),
    ];
    for row in &t.rows {
        let values = |v: usize| -> String {
            let cells: Vec<String> = row.ugr[v]
                .iter()
                .map(|&u| format!("{:>8}", cell(u)))
                .collect();
            cells.join(" ")
        };
        let room = format!("{}H   {}H", row.x_h, row.y_h);
        lines.push(format!("{room:<10} {}   {}", values(0), values(1)));
    }
    let mut values = t.rows.iter().flat_map(|r| r.ugr.iter().flatten()).flatten();
    if values.any(|&u| u < 10.0) {
        lines.push(
            "values below 10 are printed as computed (AGi32 prints them as 10, Relux as <10)"
                .into(),
        );
    }
    let corr = ugr_table::flux_correction(rated_lm);
    lines.push(format!(
        "flux correction for the file's {rated_lm:.0} lm: {corr:+.1} (8·log10(Φ/1000), add to every value)"
    ));
    let [cross, end] = t.reference();
    let shifted = |v: Option<f64>| cell(v.map(|v| v + corr));
    lines.push(format!(
        "UGR reference value (4H×8H, 70/50/20): crosswise {}, endwise {} at 1000 lm; \
         {}, {} at {rated_lm:.0} lm",
        cell(cross),
        cell(end),
        shifted(cross),
        shifted(end)
    ));
    lines
}

/// The table as CSV: one row per room, X/H, Y/H, the array's luminaires, then the ten
/// values (crosswise 70/50/20 … endwise 30/30/20); empty where no luminaire counts.
fn csv_text(t: &Table) -> String {
    let mut head = vec!["x_h".to_string(), "y_h".into(), "luminaires".into()];
    for v in View::BOTH {
        for r in REFLECTANCES {
            head.push(format!("{} {}", v.as_str(), r.label()));
        }
    }
    let mut out = head.join(",") + "\n";
    for row in &t.rows {
        let mut f = vec![
            row.x_h.to_string(),
            row.y_h.to_string(),
            row.luminaires.to_string(),
        ];
        for v in &row.ugr {
            f.extend(
                v.iter()
                    .map(|u| u.map_or(String::new(), |u| format!("{u:.2}"))),
            );
        }
        out += &(f.join(",") + "\n");
    }
    out
}
