//! Named EN 12464-1 task types: a requirement's `task = "office.writing"` fills in the
//! values the standard's table gives for the area the requirement is on (`area`: the
//! task area, its immediate surrounding and background, walls, ceiling, the cylindrical
//! illuminance, or an observer's UGR). The standard is paywalled: the values are those
//! published in public summaries of it, each row naming its edition; any key written
//! beside `task` overrides the row (docs/designers.md lists the rows).

/// One row of a requirement table.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TaskType {
    /// The name a scene gives it: `office.writing`.
    pub id: &'static str,
    /// Edition and table the values come from.
    pub source: &'static str,
    pub title: &'static str,
    /// Ēm required, lx.
    pub em: f64,
    /// Ēm modified (2021's context modifiers), lx, where the row gives one.
    pub em_modified: Option<f64>,
    pub u0: f64,
    /// R_UGL: the most UGR may be.
    pub ugr_max: f64,
    /// Ēm,z required and modified, lx, where the row gives them.
    pub ez: Option<f64>,
    pub ez_modified: Option<f64>,
    /// Ēm on the walls and on the ceiling, lx, where the row gives them.
    pub walls: Option<f64>,
    pub ceiling: Option<f64>,
}

const T2021: &str = "EN 12464-1:2021, offices";
const T2011: &str = "EN 12464-1:2011, Table 5.26 (offices)";
const T2011_EDU: &str = "EN 12464-1:2011, Table 5.36 (educational buildings)";
const T2011_TRAFFIC: &str = "EN 12464-1:2011, Table 5.1 (traffic zones)";

const fn row(id: &'static str, source: &'static str, title: &'static str) -> TaskType {
    TaskType {
        id,
        source,
        title,
        em: 0.0,
        em_modified: None,
        u0: 0.0,
        ugr_max: 0.0,
        ez: None,
        ez_modified: None,
        walls: None,
        ceiling: None,
    }
}

/// The rows luxtally knows, by id.
pub const TASK_TYPES: &[TaskType] = &[
    TaskType {
        em: 300.0,
        em_modified: Some(500.0),
        u0: 0.40,
        ugr_max: 19.0,
        ..row("office.filing", T2021, "filing, copying, etc.")
    },
    TaskType {
        em: 500.0,
        em_modified: Some(1000.0),
        u0: 0.60,
        ugr_max: 19.0,
        ez: Some(150.0),
        ez_modified: Some(250.0),
        walls: Some(150.0),
        ceiling: Some(100.0),
        ..row(
            "office.writing",
            T2021,
            "writing, typing, reading, data processing",
        )
    },
    TaskType {
        em: 750.0,
        u0: 0.70,
        ugr_max: 16.0,
        ..row("office.technical_drawing", T2011, "technical drawing")
    },
    TaskType {
        em: 500.0,
        u0: 0.60,
        ugr_max: 19.0,
        ..row("office.cad", T2011, "CAD work stations")
    },
    TaskType {
        em: 500.0,
        u0: 0.60,
        ugr_max: 19.0,
        ..row("office.conference", T2011, "conference and meeting rooms")
    },
    TaskType {
        em: 300.0,
        u0: 0.60,
        ugr_max: 22.0,
        ..row("office.reception", T2011, "reception desk")
    },
    TaskType {
        em: 200.0,
        u0: 0.40,
        ugr_max: 25.0,
        ..row("office.archives", T2011, "archives")
    },
    TaskType {
        em: 300.0,
        u0: 0.60,
        ugr_max: 19.0,
        ..row(
            "education.classroom",
            T2011_EDU,
            "classrooms, tutorial rooms",
        )
    },
    TaskType {
        em: 100.0,
        u0: 0.40,
        ugr_max: 28.0,
        ..row(
            "circulation.corridor",
            T2011_TRAFFIC,
            "circulation areas and corridors",
        )
    },
];

/// Which of a task's areas a requirement is on (`area`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Area {
    Task,
    /// The band ≥ 0.5 m around the task area: one step lower, U0 ≥ 0.40.
    Surrounding,
    /// The band ≥ 3 m beyond the surrounding: a third of the surrounding's Ē, U0 ≥ 0.10.
    Background,
    Walls,
    Ceiling,
    /// A cylindrical receiver: Ēz.
    Cylindrical,
}

impl Area {
    pub fn parse(s: &str) -> Option<Area> {
        Some(match s {
            "task" => Area::Task,
            "surrounding" => Area::Surrounding,
            "background" => Area::Background,
            "walls" => Area::Walls,
            "ceiling" => Area::Ceiling,
            "cylindrical" => Area::Cylindrical,
            _ => return None,
        })
    }

    pub const NAMES: &'static str = "task, surrounding, background, walls, ceiling or cylindrical";
}

/// Ēm of a task's immediate surrounding (the standard's task → surrounding table: one
/// step of the illuminance scale lower from 200 lx up, the task's own value below).
pub fn surrounding_em(task_em: f64) -> f64 {
    match task_em {
        e if e >= 750.0 => 500.0,
        e if e >= 500.0 => 300.0,
        e if e >= 300.0 => 200.0,
        e if e >= 200.0 => 150.0,
        e => e,
    }
}

/// U0 of the immediate surrounding and of the background.
pub const SURROUNDING_U0: f64 = 0.40;
pub const BACKGROUND_U0: f64 = 0.10;
/// U0 of walls and ceiling, and their Ēm where the row gives none (2021, enclosed
/// spaces).
pub const WALL_CEILING_U0: f64 = 0.10;
pub const WALLS_EM: f64 = 50.0;
pub const CEILING_EM: f64 = 30.0;
/// Ēm,z of an activity area where the row gives none.
pub const EZ: f64 = 50.0;

/// The values a task row sets on one area: Ē and U0 of a receiver (U0 absent for Ēz).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AreaValues {
    pub em: f64,
    pub u0: Option<f64>,
}

impl TaskType {
    pub fn find(id: &str) -> Option<&'static TaskType> {
        TASK_TYPES.iter().find(|t| t.id == id)
    }

    /// The values for `area`; `modified` takes the modified Ēm (None: the row has none).
    pub fn area_values(&self, area: Area, modified: bool) -> Option<AreaValues> {
        let em = if modified { self.em_modified? } else { self.em };
        let values = |em, u0| Some(AreaValues { em, u0 });
        match area {
            Area::Task => values(em, Some(self.u0)),
            Area::Surrounding => values(surrounding_em(em), Some(SURROUNDING_U0)),
            Area::Background => values(surrounding_em(em) / 3.0, Some(BACKGROUND_U0)),
            Area::Walls => values(self.walls.unwrap_or(WALLS_EM), Some(WALL_CEILING_U0)),
            Area::Ceiling => values(self.ceiling.unwrap_or(CEILING_EM), Some(WALL_CEILING_U0)),
            Area::Cylindrical => {
                let ez = if modified {
                    self.ez_modified?
                } else {
                    self.ez.unwrap_or(EZ)
                };
                values(ez, None)
            }
        }
    }

    /// "EN 12464-1:2021, offices: writing, …": what a verdict says its limits came from.
    pub fn describe(&self, area: Area, modified: bool) -> String {
        let area = match area {
            Area::Task => "task area",
            Area::Surrounding => "immediate surrounding",
            Area::Background => "background",
            Area::Walls => "walls",
            Area::Ceiling => "ceiling",
            Area::Cylindrical => "cylindrical illuminance",
        };
        let modified = if modified { ", modified Ēm" } else { "" };
        format!("{}: {} ({area}{modified})", self.source, self.title)
    }
}

/// The rows as a text table (`luxtally tasks`): id, Ēm (modified), U0, R_UGL, Ēz,
/// walls, ceiling, source.
pub fn table_text() -> String {
    let opt = |x: Option<f64>| x.map_or("–".to_string(), |v| format!("{v}"));
    let mut out = format!(
        "{:<26} {:>11} {:>5} {:>5} {:>9} {:>5} {:>7}  source: title\n",
        "task", "Ēm (mod.)", "U0", "R_UGL", "Ēz (mod.)", "walls", "ceiling"
    );
    for t in TASK_TYPES {
        out += &format!(
            "{:<26} {:>11} {:>5.2} {:>5} {:>9} {:>5} {:>7}  {}: {}\n",
            t.id,
            format!("{} ({})", t.em, opt(t.em_modified)),
            t.u0,
            t.ugr_max,
            format!("{} ({})", opt(t.ez), opt(t.ez_modified)),
            opt(t.walls),
            opt(t.ceiling),
            t.source,
            t.title
        );
    }
    out += &format!(
        "Surrounding: one step lower (750→500, 500→300, 300→200, 200→150, below: the \
         task's), U0 {SURROUNDING_U0}; background: a third of the surrounding's, U0 \
         {BACKGROUND_U0}; walls {WALLS_EM} lx and ceiling {CEILING_EM} lx, U0 \
         {WALL_CEILING_U0}, and Ēz {EZ} lx where a row gives none.\n"
    );
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_are_unique_and_rows_complete() {
        for (i, t) in TASK_TYPES.iter().enumerate() {
            assert!(TASK_TYPES[..i].iter().all(|o| o.id != t.id), "{}", t.id);
            assert!(t.em > 0.0 && t.u0 > 0.0 && t.u0 <= 1.0 && t.ugr_max > 0.0);
        }
    }

    #[test]
    fn areas_follow_the_standard_relations() {
        let w = TaskType::find("office.writing").unwrap();
        let at = |a, m| w.area_values(a, m).unwrap();
        assert_eq!(
            at(Area::Task, false),
            AreaValues {
                em: 500.0,
                u0: Some(0.6)
            }
        );
        assert_eq!(at(Area::Task, true).em, 1000.0);
        assert_eq!(
            at(Area::Surrounding, false),
            AreaValues {
                em: 300.0,
                u0: Some(0.4)
            }
        );
        assert_eq!(at(Area::Surrounding, true).em, 500.0);
        assert_eq!(at(Area::Background, false).em, 100.0);
        assert_eq!(
            at(Area::Cylindrical, false),
            AreaValues {
                em: 150.0,
                u0: None
            }
        );
        assert_eq!(at(Area::Walls, false).em, 150.0);
        let archives = TaskType::find("office.archives").unwrap();
        assert_eq!(
            archives.area_values(Area::Surrounding, false).unwrap().em,
            150.0
        );
        assert_eq!(
            archives.area_values(Area::Walls, false).unwrap().em,
            WALLS_EM
        );
        assert_eq!(archives.area_values(Area::Task, true), None);
        let corridor = TaskType::find("circulation.corridor").unwrap();
        assert_eq!(
            corridor.area_values(Area::Surrounding, false).unwrap().em,
            100.0
        );
    }
}
