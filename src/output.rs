//! MCAP output streamed while the engine runs: metadata, the scenario as an
//! attachment, and one channel per output kind. Messages are JSON with a
//! JSON Schema (MCAP well-known encodings); chunks are zstd-compressed and
//! flushed every few seconds so that a killed run leaves a readable file.

use crate::engine::Snapshot;
use crate::model::Model;
use crate::scenario::Scenario;
use serde::Serialize;
use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::Path;
use std::time::{Duration, Instant};

const FLUSH_EVERY: Duration = Duration::from_secs(2);

#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("cannot create `{path}`: {source}")]
    Create {
        path: String,
        source: std::io::Error,
    },
    #[error("MCAP: {0}")]
    Mcap(#[from] mcap::McapError),
    #[error("JSON: {0}")]
    Json(#[from] serde_json::Error),
}

/// One sample of the global series.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct GlobalSample {
    pub time: f64,
    pub step: u64,
    pub drive_force: f64,
    pub drive_ratio: f64,
    pub friction_force: f64,
    pub pinned_fraction: f64,
    pub kinetic_energy: f64,
    pub ruptures: u64,
}

#[derive(Serialize)]
struct InterfaceMessage<'a> {
    time: f64,
    step: u64,
    shear_stress: &'a [f64],
    normal_stress: &'a [f64],
    pinned_fraction: &'a [f64],
    slip: &'a [f64],
    slip_speed: &'a [f64],
}

#[derive(Serialize)]
struct BulkMessage<'a> {
    time: f64,
    step: u64,
    nx: usize,
    nz: usize,
    ux: &'a [f64],
    uz: &'a [f64],
    vx: &'a [f64],
    vz: &'a [f64],
}

pub struct McapSink {
    writer: mcap::Writer<BufWriter<File>>,
    global: u16,
    interface: u16,
    bulk: u16,
    sequence: u32,
    last_flush: Instant,
    slip_origin: Option<Vec<f64>>,
}

fn schema(properties: &[&str], arrays: &[&str]) -> Vec<u8> {
    let mut props = serde_json::Map::new();
    for p in properties {
        props.insert(p.to_string(), serde_json::json!({"type": "number"}));
    }
    for a in arrays {
        props.insert(
            a.to_string(),
            serde_json::json!({"type": "array", "items": {"type": "number"}}),
        );
    }
    serde_json::to_vec(&serde_json::json!({"type": "object", "properties": props}))
        .expect("schema serialises")
}

impl McapSink {
    pub fn create(
        path: &Path,
        model: &Model,
        scenario: &Scenario,
        backend: &str,
    ) -> Result<Self, OutputError> {
        let file = File::create(path).map_err(|source| OutputError::Create {
            path: path.display().to_string(),
            source,
        })?;
        let mut writer = mcap::WriteOptions::new()
            .compression(Some(mcap::Compression::Zstd))
            .chunk_size(Some(1 << 20))
            .create(BufWriter::new(file))?;
        let toml = scenario.to_toml();
        let mut meta = BTreeMap::new();
        meta.insert("slipfront_version".into(), env!("CARGO_PKG_VERSION").into());
        meta.insert(
            "git_commit".into(),
            option_env!("SLIPFRONT_GIT_COMMIT")
                .unwrap_or("unknown")
                .into(),
        );
        meta.insert("scenario".into(), scenario.name.clone());
        meta.insert(
            "scenario_hash".into(),
            format!("{:016x}", fnv1a(toml.as_bytes())),
        );
        meta.insert("backend".into(), backend.into());
        meta.insert("seed".into(), model.seed.to_string());
        meta.insert("dt".into(), format!("{:e}", model.dt));
        meta.insert("nx".into(), model.nx.to_string());
        meta.insert("nz".into(), model.nz.to_string());
        meta.insert("spacing".into(), format!("{:e}", model.spacing));
        meta.insert("normal_force".into(), format!("{:e}", model.normal_force));
        writer.write_metadata(&mcap::records::Metadata {
            name: "slipfront".into(),
            metadata: meta,
        })?;
        writer.attach(&mcap::Attachment {
            log_time: 0,
            create_time: 0,
            name: "scenario.toml".into(),
            media_type: "application/toml".into(),
            data: std::borrow::Cow::Owned(toml.into_bytes()),
        })?;
        let g = writer.add_schema(
            "slipfront.Global",
            "jsonschema",
            &schema(
                &[
                    "time",
                    "step",
                    "drive_force",
                    "drive_ratio",
                    "friction_force",
                    "pinned_fraction",
                    "kinetic_energy",
                    "ruptures",
                ],
                &[],
            ),
        )?;
        let i = writer.add_schema(
            "slipfront.Interface",
            "jsonschema",
            &schema(
                &["time", "step"],
                &[
                    "shear_stress",
                    "normal_stress",
                    "pinned_fraction",
                    "slip",
                    "slip_speed",
                ],
            ),
        )?;
        let b = writer.add_schema(
            "slipfront.Bulk",
            "jsonschema",
            &schema(&["time", "step", "nx", "nz"], &["ux", "uz", "vx", "vz"]),
        )?;
        let none = BTreeMap::new();
        let global = writer.add_channel(g, "/global", "json", &none)?;
        let interface = writer.add_channel(i, "/interface", "json", &none)?;
        let bulk = writer.add_channel(b, "/bulk", "json", &none)?;
        Ok(McapSink {
            writer,
            global,
            interface,
            bulk,
            sequence: 0,
            last_flush: Instant::now(),
            slip_origin: None,
        })
    }

    fn write(&mut self, channel: u16, time: f64, data: &[u8]) -> Result<(), OutputError> {
        let t = (time.max(0.0) * 1e9) as u64;
        self.sequence += 1;
        self.writer.write_to_known_channel(
            &mcap::records::MessageHeader {
                channel_id: channel,
                sequence: self.sequence,
                log_time: t,
                publish_time: t,
            },
            data,
        )?;
        if self.last_flush.elapsed() > FLUSH_EVERY {
            self.writer.flush()?;
            self.last_flush = Instant::now();
        }
        Ok(())
    }

    pub fn write_global(&mut self, g: &GlobalSample) -> Result<(), OutputError> {
        let data = serde_json::to_vec(g)?;
        self.write(self.global, g.time, &data)
    }

    pub fn write_interface(&mut self, model: &Model, snap: &Snapshot) -> Result<(), OutputError> {
        let area = model.spacing * model.width;
        let ux: Vec<f64> = (0..model.nx).map(|ix| snap.disp[ix][0]).collect();
        let origin = self.slip_origin.get_or_insert_with(|| ux.clone());
        let slip: Vec<f64> = ux.iter().zip(origin.iter()).map(|(u, o)| u - o).collect();
        let shear: Vec<f64> = snap.friction.iter().map(|f| -f / area).collect();
        let normal: Vec<f64> = snap.normal.iter().map(|p| p / area).collect();
        let speed: Vec<f64> = (0..model.nx).map(|ix| snap.vel[ix][0]).collect();
        let msg = InterfaceMessage {
            time: snap.time,
            step: snap.step,
            shear_stress: &shear,
            normal_stress: &normal,
            pinned_fraction: &snap.pinned_fraction(model.nx),
            slip: &slip,
            slip_speed: &speed,
        };
        let data = serde_json::to_vec(&msg)?;
        self.write(self.interface, snap.time, &data)
    }

    pub fn write_bulk(&mut self, model: &Model, snap: &Snapshot) -> Result<(), OutputError> {
        let ux: Vec<f64> = snap.disp.iter().map(|u| u[0]).collect();
        let uz: Vec<f64> = snap.disp.iter().map(|u| u[1]).collect();
        let vx: Vec<f64> = snap.vel.iter().map(|v| v[0]).collect();
        let vz: Vec<f64> = snap.vel.iter().map(|v| v[1]).collect();
        let msg = BulkMessage {
            time: snap.time,
            step: snap.step,
            nx: model.nx,
            nz: model.nz,
            ux: &ux,
            uz: &uz,
            vx: &vx,
            vz: &vz,
        };
        let data = serde_json::to_vec(&msg)?;
        self.write(self.bulk, snap.time, &data)
    }

    pub fn finish(mut self) -> Result<(), OutputError> {
        self.writer.finish()?;
        Ok(())
    }
}

/// FNV-1a 64-bit hash (scenario fingerprint).
pub fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0100_0000_01b3)
    })
}
