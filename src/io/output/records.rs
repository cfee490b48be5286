//! The records of a run's channels. Each is built once from the engine's
//! samples and sent, as the same protobuf bytes, to the run file and to the
//! live view; a replay decodes them back from the file.

use super::messages::{Bulk, FastForwardJump, Global, Interface};
use super::GlobalSample;
use crate::engines::quasistatic::JumpRecord;
use crate::engines::{BulkField, InterfaceRow};
use crate::model::Model;
use prost::Message;

/// A channel of the run file (and of the live view).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Topic {
    Global,
    Interface,
    Bulk,
    FastForward,
}

impl Topic {
    pub const ALL: [Topic; 4] = [
        Topic::Global,
        Topic::Interface,
        Topic::Bulk,
        Topic::FastForward,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Topic::Global => "/global",
            Topic::Interface => "/interface",
            Topic::Bulk => "/bulk",
            Topic::FastForward => "/fast_forward",
        }
    }

    /// The protobuf message type of the channel (in `slipfront.proto`).
    pub fn schema(self) -> &'static str {
        match self {
            Topic::Global => "slipfront.Global",
            Topic::Interface => "slipfront.Interface",
            Topic::Bulk => "slipfront.Bulk",
            Topic::FastForward => "slipfront.FastForwardJump",
        }
    }

    pub fn from_name(name: &str) -> Option<Topic> {
        Topic::ALL.into_iter().find(|t| t.name() == name)
    }

    /// Position in [`Topic::ALL`].
    pub fn index(self) -> usize {
        self as usize
    }
}

/// One message of a channel, decoded.
#[derive(Clone, Debug, PartialEq)]
pub enum Record {
    Global(Global),
    Interface(Interface),
    Bulk(Bulk),
    FastForward(FastForwardJump),
}

impl Record {
    pub fn topic(&self) -> Topic {
        match self {
            Record::Global(_) => Topic::Global,
            Record::Interface(_) => Topic::Interface,
            Record::Bulk(_) => Topic::Bulk,
            Record::FastForward(_) => Topic::FastForward,
        }
    }

    /// The simulated instant it is logged at (s): a sample's time, a
    /// jump's end.
    pub fn time(&self) -> f64 {
        match self {
            Record::Global(m) => m.time,
            Record::Interface(m) => m.time,
            Record::Bulk(m) => m.time,
            Record::FastForward(m) => m.end_time,
        }
    }

    pub fn encode(&self) -> Vec<u8> {
        match self {
            Record::Global(m) => m.encode_to_vec(),
            // The arrays copied whole (`packed`): the same bytes.
            Record::Interface(m) => super::packed::encode_interface(m),
            Record::Bulk(m) => super::packed::encode_bulk(m),
            Record::FastForward(m) => m.encode_to_vec(),
        }
    }

    pub fn decode(topic: Topic, data: &[u8]) -> Result<Record, prost::DecodeError> {
        Ok(match topic {
            Topic::Global => Record::Global(Global::decode(data)?),
            Topic::Interface => Record::Interface(Interface::decode(data)?),
            Topic::Bulk => Record::Bulk(Bulk::decode(data)?),
            Topic::FastForward => Record::FastForward(FastForwardJump::decode(data)?),
        })
    }
}

/// The log time (ns) of simulated time `t` (s), in the file and on the
/// live view alike.
pub fn log_time(t: f64) -> u64 {
    (t.max(0.0) * 1e9) as u64
}

/// Builds the records from the engine's samples. The channels' units are
/// set here, once: stresses per block area, shear stress with the sign of
/// the drive, slip from the first interface row built.
#[derive(Debug, Default, Clone)]
pub struct RecordBuilder {
    slip_origin: Option<Vec<f64>>,
}

impl RecordBuilder {
    /// Continues the slip origin of a saved run.
    pub fn restored(slip_origin: Option<Vec<f64>>) -> Self {
        RecordBuilder { slip_origin }
    }

    /// The interface's u_x at the first row built (a checkpoint keeps it).
    pub fn slip_origin(&self) -> Option<Vec<f64>> {
        self.slip_origin.clone()
    }

    pub fn global(g: &GlobalSample) -> Record {
        Record::Global(Global {
            time: g.time,
            step: g.step,
            drive_force: g.drive_force,
            drive_ratio: g.drive_ratio,
            friction_force: g.friction_force,
            pinned_fraction: g.pinned_fraction,
            kinetic_energy: g.kinetic_energy,
            ruptures: g.ruptures,
        })
    }

    pub fn interface(&mut self, model: &Model, step: u64, time: f64, row: &InterfaceRow) -> Record {
        let area = model.spacing * model.width;
        let origin = self.slip_origin.get_or_insert_with(|| row.ux.clone());
        Record::Interface(Interface {
            time,
            step,
            shear_stress: row.friction.iter().map(|f| -f / area).collect(),
            normal_stress: row.normal.iter().map(|p| p / area).collect(),
            pinned_fraction: row.pinned_fraction.clone(),
            slip: row
                .ux
                .iter()
                .zip(origin.iter())
                .map(|(u, o)| u - o)
                .collect(),
            slip_speed: row.slip_speed.clone(),
        })
    }

    pub fn bulk(model: &Model, step: u64, time: f64, field: &BulkField) -> Record {
        Record::Bulk(Bulk {
            time,
            step,
            nx: model.nx as u32,
            nz: model.nz as u32,
            ux: field.ux.clone(),
            uz: field.uz.clone(),
            vx: field.vx.clone(),
            vz: field.vz.clone(),
        })
    }

    pub fn fast_forward(r: &JumpRecord) -> Record {
        let index = |v: Option<usize>| v.map_or(-1, |v| v as i32);
        Record::FastForward(FastForwardJump {
            start_time: r.start_time,
            end_time: r.end_time,
            start_step: r.start_step,
            end_step: r.end_step,
            drive_start: r.drive_start,
            drive_end: r.drive_end,
            predicted_change: r.predicted_change,
            block: index(r.block),
            junction: index(r.junction),
            dropped_energy: r.dropped_energy,
            work_in: r.work_in,
            damping: r.damping,
            stored_change: r.stored_change,
            ruptures: r.ruptures,
            repins: r.repins,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn topics_round_trip_by_name_and_records_by_bytes() {
        for t in Topic::ALL {
            assert_eq!(Topic::from_name(t.name()), Some(t));
            assert_eq!(Topic::ALL[t.index()], t);
        }
        assert_eq!(Topic::from_name("/nope"), None);
        let r = Record::Bulk(Bulk {
            time: 0.25,
            nx: 2,
            nz: 1,
            ux: vec![1.0, -2.5],
            ..Default::default()
        });
        let back = Record::decode(Topic::Bulk, &r.encode()).unwrap();
        assert_eq!(back, r);
        assert_eq!(back.time(), 0.25);
        assert_eq!(log_time(0.25), 250_000_000);
        assert_eq!(log_time(-1.0), 0);
    }
}
