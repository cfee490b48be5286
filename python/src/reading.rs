//! `slipfront.open`: a run file (complete, or cut short by a killed run)
//! decoded in Rust and handed to Python as numpy arrays, one contiguous
//! array per channel field; and the event table of an interface series.

use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2};
use prost::Message;
use pyo3::exceptions::{PyFileNotFoundError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use slipfront::analysis::event_table::event_rows;
use slipfront::analysis::events::InterfaceSeries;
use slipfront::analysis::precursors::PrecursorSequence;
use slipfront::io::output::messages::{Bulk, FastForwardJump, Global, Interface};
use slipfront::io::output::reader::{memory_budget, times_go_forward, ChannelSink, RunFile};
use slipfront::io::output::records::Topic;
use std::path::PathBuf;

/// One column: its numbers, and its shape (rows first).
enum Column {
    F64(Vec<f64>, Vec<usize>),
    F32(Vec<f32>, Vec<usize>),
    U64(Vec<u64>),
    I32(Vec<i32>),
}

/// Columns of numbers, by name, in the order they are added.
#[derive(Default)]
struct Columns(Vec<(&'static str, Column)>);

impl Columns {
    fn f64<T>(&mut self, name: &'static str, rows: &[T], get: impl Fn(&T) -> f64) {
        let n = rows.len();
        self.0
            .push((name, Column::F64(rows.iter().map(get).collect(), vec![n])));
    }

    fn u64<T>(&mut self, name: &'static str, rows: &[T], get: impl Fn(&T) -> u64) {
        self.0
            .push((name, Column::U64(rows.iter().map(get).collect())));
    }

    fn i32<T>(&mut self, name: &'static str, rows: &[T], get: impl Fn(&T) -> i32) {
        self.0
            .push((name, Column::I32(rows.iter().map(get).collect())));
    }

    /// The columns as a dict of numpy arrays (the vectors move into numpy,
    /// uncopied).
    fn into_dict(self, py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
        let d = PyDict::new(py);
        for (name, column) in self.0 {
            match column {
                Column::F64(v, dims) => {
                    d.set_item(name, PyArray1::from_vec(py, v).reshape(dims)?)?
                }
                Column::F32(v, dims) => {
                    d.set_item(name, PyArray1::from_vec(py, v).reshape(dims)?)?
                }
                Column::U64(v) => d.set_item(name, PyArray1::from_vec(py, v))?,
                Column::I32(v) => d.set_item(name, PyArray1::from_vec(py, v))?,
            }
        }
        Ok(d)
    }
}

/// The channels decoded straight into flat columns as the file is read
/// (no message kept: one scratch message per channel, its vectors reused).
#[derive(Default)]
struct ColumnSink {
    global: Vec<Global>,
    interface_time: Vec<f64>,
    interface_step: Vec<u64>,
    /// shear_stress, normal_stress, pinned_fraction, slip, slip_speed.
    interface_fields: [Vec<f64>; 5],
    interface_nx: Option<usize>,
    bulk_time: Vec<f64>,
    bulk_step: Vec<u64>,
    /// ux, uz, vx, vz.
    bulk_fields: [Vec<f32>; 4],
    bulk_shape: Option<(usize, usize)>,
    jumps: Vec<FastForwardJump>,
    scratch_interface: Interface,
    scratch_bulk: Bulk,
}

impl ChannelSink for ColumnSink {
    fn message(&mut self, topic: Topic, data: &[u8]) -> Result<(), String> {
        let e = |e: prost::DecodeError| e.to_string();
        match topic {
            Topic::Global => self.global.push(Global::decode(data).map_err(e)?),
            Topic::FastForward => self.jumps.push(FastForwardJump::decode(data).map_err(e)?),
            Topic::Interface => {
                let m = &mut self.scratch_interface;
                m.clear();
                m.merge(data).map_err(e)?;
                let rows = [
                    &m.shear_stress,
                    &m.normal_stress,
                    &m.pinned_fraction,
                    &m.slip,
                    &m.slip_speed,
                ];
                let nx = *self.interface_nx.get_or_insert(m.slip.len());
                if rows.iter().any(|r| r.len() != nx) {
                    let lengths: Vec<usize> = rows.iter().map(|r| r.len()).collect();
                    return Err(format!(
                        "damaged: /interface message {} (t = {:e} s) has rows of lengths \
                         {lengths:?}, the interface has {nx} blocks",
                        self.interface_time.len(),
                        m.time
                    ));
                }
                for (column, row) in self.interface_fields.iter_mut().zip(rows) {
                    column.extend_from_slice(row);
                }
                self.interface_time.push(m.time);
                self.interface_step.push(m.step);
            }
            Topic::Bulk => {
                let m = &mut self.scratch_bulk;
                m.clear();
                m.merge(data).map_err(e)?;
                let shape = *self
                    .bulk_shape
                    .get_or_insert((m.nz as usize, m.nx as usize));
                let fields = [&m.ux, &m.uz, &m.vx, &m.vz];
                if (m.nz as usize, m.nx as usize) != shape
                    || fields.iter().any(|f| f.len() != shape.0 * shape.1)
                {
                    return Err(format!(
                        "damaged: /bulk message {} (t = {:e} s) is not a {} × {} field",
                        self.bulk_time.len(),
                        m.time,
                        shape.0,
                        shape.1
                    ));
                }
                for (column, field) in self.bulk_fields.iter_mut().zip(fields) {
                    column.extend_from_slice(field);
                }
                self.bulk_time.push(m.time);
                self.bulk_step.push(m.step);
            }
        }
        Ok(())
    }

    fn check(&self, nx: Option<usize>) -> Result<(), String> {
        if let (Some(nx), Some(rows)) = (nx, self.interface_nx) {
            if nx != rows {
                return Err(format!(
                    "damaged: /interface rows of {rows} blocks, the interface has {nx}"
                ));
            }
        }
        times_go_forward("/global", self.global.iter().map(|m| m.time))?;
        times_go_forward("/interface", self.interface_time.iter().copied())?;
        times_go_forward("/bulk", self.bulk_time.iter().copied())
    }
}

/// A run file's channels as columns (read without the GIL).
struct Decoded {
    head: RunFile,
    series: Columns,
    interface: Columns,
    bulk: Columns,
    bulk_shape: Option<(usize, usize)>,
    jumps: Columns,
}

fn decode(path: &std::path::Path) -> Result<Decoded, String> {
    let mut sink = ColumnSink::default();
    let head = RunFile::read_with(path, memory_budget(), &mut sink).map_err(|e| e.to_string())?;
    let mut series = Columns::default();
    let g = &sink.global;
    series.f64("time", g, |m| m.time);
    series.u64("step", g, |m| m.step);
    series.f64("drive_force", g, |m| m.drive_force);
    series.f64("drive_ratio", g, |m| m.drive_ratio);
    series.f64("friction_force", g, |m| m.friction_force);
    series.f64("pinned_fraction", g, |m| m.pinned_fraction);
    series.f64("kinetic_energy", g, |m| m.kinetic_energy);
    series.u64("ruptures", g, |m| m.ruptures);

    let rows = sink.interface_time.len();
    let nx = sink.interface_nx.unwrap_or(0);
    let mut interface = Columns::default();
    interface
        .0
        .push(("time", Column::F64(sink.interface_time, vec![rows])));
    interface.0.push(("step", Column::U64(sink.interface_step)));
    let names = [
        "shear_stress",
        "normal_stress",
        "pinned_fraction",
        "slip",
        "slip_speed",
    ];
    for (name, column) in names.into_iter().zip(sink.interface_fields) {
        interface
            .0
            .push((name, Column::F64(column, vec![rows, nx])));
    }

    let mut bulk = Columns::default();
    if let Some((nz, nx)) = sink.bulk_shape {
        let rows = sink.bulk_time.len();
        bulk.0
            .push(("time", Column::F64(sink.bulk_time, vec![rows])));
        bulk.0.push(("step", Column::U64(sink.bulk_step)));
        for (name, column) in ["ux", "uz", "vx", "vz"].into_iter().zip(sink.bulk_fields) {
            bulk.0.push((name, Column::F32(column, vec![rows, nz, nx])));
        }
    }

    let j = &sink.jumps;
    let mut jumps = Columns::default();
    jumps.f64("start_time", j, |m| m.start_time);
    jumps.f64("end_time", j, |m| m.end_time);
    jumps.u64("start_step", j, |m| m.start_step);
    jumps.u64("end_step", j, |m| m.end_step);
    jumps.f64("drive_start", j, |m| m.drive_start);
    jumps.f64("drive_end", j, |m| m.drive_end);
    jumps.f64("predicted_change", j, |m| m.predicted_change);
    jumps.i32("block", j, |m| m.block);
    jumps.i32("junction", j, |m| m.junction);
    jumps.f64("dropped_energy", j, |m| m.dropped_energy);
    jumps.f64("work_in", j, |m| m.work_in);
    jumps.f64("damping", j, |m| m.damping);
    jumps.f64("stored_change", j, |m| m.stored_change);
    jumps.u64("ruptures", j, |m| m.ruptures);
    jumps.u64("repins", j, |m| m.repins);

    Ok(Decoded {
        head,
        series,
        interface,
        bulk,
        bulk_shape: sink.bulk_shape,
        jumps,
    })
}

/// Reads a run file into a dict: `metadata`, `scenario` (TOML text),
/// `history`, `truncated`, `damage`, `spacing`, and the channels `series`
/// (/global), `interface` (time × block), `bulk` (time × nz × nx, f32) and
/// `jumps` (/fast_forward), each a dict of numpy arrays.
#[pyfunction]
pub fn read_run(py: Python<'_>, path: PathBuf) -> PyResult<Bound<'_, PyDict>> {
    if !path.exists() {
        return Err(PyFileNotFoundError::new_err(format!(
            "no run file `{}`",
            path.display()
        )));
    }
    let d = py.detach(|| decode(&path)).map_err(PyValueError::new_err)?;
    let out = PyDict::new(py);
    out.set_item("path", path.display().to_string())?;
    out.set_item("spacing", d.head.spacing())?;
    out.set_item("metadata", d.head.metadata)?;
    out.set_item("scenario", d.head.scenario)?;
    out.set_item("history", d.head.history)?;
    out.set_item("truncated", d.head.truncated)?;
    out.set_item("damage", d.head.damage)?;
    out.set_item("fast_forward_totals", d.head.fast_forward_totals)?;
    out.set_item("series", d.series.into_dict(py)?)?;
    out.set_item("interface", d.interface.into_dict(py)?)?;
    out.set_item("bulk_shape", d.bulk_shape)?;
    out.set_item("bulk", d.bulk.into_dict(py)?)?;
    out.set_item("jumps", d.jumps.into_dict(py)?)?;
    Ok(out)
}

/// The events of an interface series (`slipfront info`'s table) and the
/// precursors before the first full event: returns (events, precursors,
/// F/F_N at the first full event or None); events and precursors are dicts
/// of columns.
#[pyfunction]
#[pyo3(signature = (time, pinned_fraction, slip, slip_speed, spacing, series_time,
                    drive_ratio, quiet_gap=slipfront::analysis::events::DEFAULT_QUIET_GAP))]
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
pub fn event_table<'py>(
    py: Python<'py>,
    time: PyReadonlyArray1<'py, f64>,
    pinned_fraction: PyReadonlyArray2<'py, f64>,
    slip: PyReadonlyArray2<'py, f64>,
    slip_speed: PyReadonlyArray2<'py, f64>,
    spacing: f64,
    series_time: PyReadonlyArray1<'py, f64>,
    drive_ratio: PyReadonlyArray1<'py, f64>,
    quiet_gap: f64,
) -> PyResult<(Bound<'py, PyDict>, Bound<'py, PyDict>, Option<f64>)> {
    if !(quiet_gap.is_finite() && quiet_gap >= 0.0) {
        return Err(PyValueError::new_err(format!(
            "quiet_gap = {quiet_gap}: expected seconds, finite, 0 or more"
        )));
    }
    let rows = |a: &PyReadonlyArray2<'py, f64>| -> Vec<Vec<f64>> {
        a.as_array().outer_iter().map(|r| r.to_vec()).collect()
    };
    let series = InterfaceSeries {
        time: time.as_array().to_vec(),
        spacing,
        pinned: rows(&pinned_fraction),
        slip: rows(&slip),
        slip_speed: rows(&slip_speed),
    };
    let n = series.time.len();
    if [
        series.pinned.len(),
        series.slip.len(),
        series.slip_speed.len(),
    ] != [n; 3]
    {
        return Err(PyValueError::new_err(
            "time, pinned_fraction, slip and slip_speed need one row per time",
        ));
    }
    // F/F_N at a time: the global sample nearest to it, as `info` reads it.
    let global = RunFile {
        global: series_time
            .as_array()
            .iter()
            .zip(drive_ratio.as_array().iter())
            .map(|(&time, &drive_ratio)| Global {
                time,
                drive_ratio,
                ..Global::default()
            })
            .collect(),
        ..RunFile::default()
    };
    let table = py.detach(|| event_rows(&series, quiet_gap, |t| global.drive_ratio_at(t)));
    let events = PyDict::new(py);
    let col = |f: &dyn Fn(&(_, _)) -> f64| table.iter().map(f).collect::<Vec<f64>>();
    let nan = f64::NAN;
    events.set_item("start", col(&|(e, _)| e.start))?;
    events.set_item("end", col(&|(e, _)| e.end))?;
    events.set_item(
        "kind",
        table.iter().map(|(_, r)| r.kind).collect::<Vec<_>>(),
    )?;
    events.set_item("rupture_length", col(&|(e, _)| e.rupture_length))?;
    events.set_item("origin", col(&|(_, r)| r.origin))?;
    events.set_item("mean_slip", col(&|(e, _)| e.slip))?;
    events.set_item("drive_ratio", col(&|(_, r)| r.drive_ratio))?;
    events.set_item(
        "front",
        table
            .iter()
            .map(|(_, r)| r.front.clone())
            .collect::<Vec<_>>(),
    )?;
    events.set_item("v_front_min", col(&|(_, r)| r.speeds.map_or(nan, |s| s.0)))?;
    events.set_item("v_front_max", col(&|(_, r)| r.speeds.map_or(nan, |s| s.1)))?;
    events.set_item(
        "v_front_unresolved_at_least",
        col(&|(_, r)| r.bound.unwrap_or(nan)),
    )?;
    let just_events: Vec<_> = table.iter().map(|(e, _)| e.clone()).collect();
    let seq =
        PrecursorSequence::from_events(&just_events, spacing, |e| global.drive_ratio_at(e.start));
    let precursors = PyDict::new(py);
    let p = &seq.precursors;
    precursors.set_item(
        "drive_ratio",
        p.iter().map(|p| p.drive_ratio).collect::<Vec<_>>(),
    )?;
    precursors.set_item("length", p.iter().map(|p| p.length).collect::<Vec<_>>())?;
    precursors.set_item("origin", p.iter().map(|p| p.origin).collect::<Vec<_>>())?;
    precursors.set_item(
        "from_trailing_edge",
        p.iter()
            .map(|p| p.at_trailing_edge(spacing))
            .collect::<Vec<_>>(),
    )?;
    Ok((events, precursors, seq.first_full_ratio))
}
