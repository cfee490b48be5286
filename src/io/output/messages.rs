//! The protobuf messages of the MCAP channels and their schema (a
//! FileDescriptorSet built here, so readers such as Foxglove and the `mcap`
//! Python package decode the channels as numeric arrays).

use prost::Message;
use prost_types::field_descriptor_proto::{Label, Type};
use prost_types::{DescriptorProto, FieldDescriptorProto, FileDescriptorProto, FileDescriptorSet};

/// `/global`: one sample of the global series.
#[derive(Clone, PartialEq, Message)]
pub struct Global {
    #[prost(double, tag = "1")]
    pub time: f64,
    #[prost(uint64, tag = "2")]
    pub step: u64,
    #[prost(double, tag = "3")]
    pub drive_force: f64,
    #[prost(double, tag = "4")]
    pub drive_ratio: f64,
    #[prost(double, tag = "5")]
    pub friction_force: f64,
    #[prost(double, tag = "6")]
    pub pinned_fraction: f64,
    #[prost(double, tag = "7")]
    pub kinetic_energy: f64,
    #[prost(uint64, tag = "8")]
    pub ruptures: u64,
}

/// `/interface`: per interface block, index ix.
#[derive(Clone, PartialEq, Message)]
pub struct Interface {
    #[prost(double, tag = "1")]
    pub time: f64,
    #[prost(uint64, tag = "2")]
    pub step: u64,
    /// Pa
    #[prost(double, repeated, tag = "3")]
    pub shear_stress: Vec<f64>,
    /// Pa
    #[prost(double, repeated, tag = "4")]
    pub normal_stress: Vec<f64>,
    #[prost(double, repeated, tag = "5")]
    pub pinned_fraction: Vec<f64>,
    /// m, since the start of driving
    #[prost(double, repeated, tag = "6")]
    pub slip: Vec<f64>,
    /// m/s
    #[prost(double, repeated, tag = "7")]
    pub slip_speed: Vec<f64>,
}

/// `/bulk`: displacement and velocity fields, index iz·nx + ix.
#[derive(Clone, PartialEq, Message)]
pub struct Bulk {
    #[prost(double, tag = "1")]
    pub time: f64,
    #[prost(uint64, tag = "2")]
    pub step: u64,
    #[prost(uint32, tag = "3")]
    pub nx: u32,
    #[prost(uint32, tag = "4")]
    pub nz: u32,
    #[prost(float, repeated, tag = "5")]
    pub ux: Vec<f32>,
    #[prost(float, repeated, tag = "6")]
    pub uz: Vec<f32>,
    #[prost(float, repeated, tag = "7")]
    pub vx: Vec<f32>,
    #[prost(float, repeated, tag = "8")]
    pub vz: Vec<f32>,
}

/// `/fast_forward`: one quasi-static jump. Block and junction are −1 when
/// no rupture sets the end (a contact change, or the end of the run).
#[derive(Clone, PartialEq, Message)]
pub struct FastForwardJump {
    #[prost(double, tag = "1")]
    pub start_time: f64,
    #[prost(double, tag = "2")]
    pub end_time: f64,
    #[prost(uint64, tag = "3")]
    pub start_step: u64,
    #[prost(uint64, tag = "4")]
    pub end_step: u64,
    #[prost(double, tag = "5")]
    pub drive_start: f64,
    #[prost(double, tag = "6")]
    pub drive_end: f64,
    #[prost(double, tag = "7")]
    pub predicted_change: f64,
    #[prost(int32, tag = "8")]
    pub block: i32,
    #[prost(int32, tag = "9")]
    pub junction: i32,
    /// J
    #[prost(double, tag = "10")]
    pub dropped_energy: f64,
    /// J
    #[prost(double, tag = "11")]
    pub work_in: f64,
    /// J
    #[prost(double, tag = "12")]
    pub damping: f64,
    /// J
    #[prost(double, tag = "13")]
    pub stored_change: f64,
    /// Isolated junction ruptures and re-pins done on the path.
    #[prost(uint64, tag = "14")]
    pub ruptures: u64,
    #[prost(uint64, tag = "15")]
    pub repins: u64,
}

fn field(name: &str, number: i32, ty: Type, repeated: bool) -> FieldDescriptorProto {
    FieldDescriptorProto {
        name: Some(name.into()),
        number: Some(number),
        label: Some(if repeated {
            Label::Repeated
        } else {
            Label::Optional
        } as i32),
        r#type: Some(ty as i32),
        json_name: Some(name.into()),
        ..Default::default()
    }
}

fn message(name: &str, fields: Vec<FieldDescriptorProto>) -> DescriptorProto {
    DescriptorProto {
        name: Some(name.into()),
        field: fields,
        ..Default::default()
    }
}

/// The serialized FileDescriptorSet of `slipfront.proto` (all four messages).
pub fn descriptor_set() -> Vec<u8> {
    use Type::{Double, Float, Int32, Uint32, Uint64};
    let global = message(
        "Global",
        vec![
            field("time", 1, Double, false),
            field("step", 2, Uint64, false),
            field("drive_force", 3, Double, false),
            field("drive_ratio", 4, Double, false),
            field("friction_force", 5, Double, false),
            field("pinned_fraction", 6, Double, false),
            field("kinetic_energy", 7, Double, false),
            field("ruptures", 8, Uint64, false),
        ],
    );
    let interface = message(
        "Interface",
        vec![
            field("time", 1, Double, false),
            field("step", 2, Uint64, false),
            field("shear_stress", 3, Double, true),
            field("normal_stress", 4, Double, true),
            field("pinned_fraction", 5, Double, true),
            field("slip", 6, Double, true),
            field("slip_speed", 7, Double, true),
        ],
    );
    let bulk = message(
        "Bulk",
        vec![
            field("time", 1, Double, false),
            field("step", 2, Uint64, false),
            field("nx", 3, Uint32, false),
            field("nz", 4, Uint32, false),
            field("ux", 5, Float, true),
            field("uz", 6, Float, true),
            field("vx", 7, Float, true),
            field("vz", 8, Float, true),
        ],
    );
    let fast_forward = message(
        "FastForwardJump",
        vec![
            field("start_time", 1, Double, false),
            field("end_time", 2, Double, false),
            field("start_step", 3, Uint64, false),
            field("end_step", 4, Uint64, false),
            field("drive_start", 5, Double, false),
            field("drive_end", 6, Double, false),
            field("predicted_change", 7, Double, false),
            field("block", 8, Int32, false),
            field("junction", 9, Int32, false),
            field("dropped_energy", 10, Double, false),
            field("work_in", 11, Double, false),
            field("damping", 12, Double, false),
            field("stored_change", 13, Double, false),
            field("ruptures", 14, Uint64, false),
            field("repins", 15, Uint64, false),
        ],
    );
    FileDescriptorSet {
        file: vec![FileDescriptorProto {
            name: Some("slipfront.proto".into()),
            package: Some("slipfront".into()),
            message_type: vec![global, interface, bulk, fast_forward],
            syntax: Some("proto3".into()),
            ..Default::default()
        }],
    }
    .encode_to_vec()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn descriptor_matches_the_derived_messages() {
        let set = FileDescriptorSet::decode(&descriptor_set()[..]).unwrap();
        let file = &set.file[0];
        assert_eq!(file.package.as_deref(), Some("slipfront"));
        let names: Vec<_> = file
            .message_type
            .iter()
            .map(|m| m.name().to_string())
            .collect();
        assert_eq!(names, ["Global", "Interface", "Bulk", "FastForwardJump"]);
        // A message encoded by the derive decodes field by field as described:
        // tag 3 of Interface is a packed repeated double.
        let m = Interface {
            shear_stress: vec![1.5, -2.0],
            ..Default::default()
        };
        let bytes = m.encode_to_vec();
        assert_eq!(bytes[0], (3 << 3) | 2, "field 3, length-delimited (packed)");
        assert_eq!(bytes[1], 16);
        assert_eq!(f64::from_le_bytes(bytes[2..10].try_into().unwrap()), 1.5);
        let f = &file.message_type[1].field[2];
        assert_eq!(
            (f.name(), f.number(), f.label(), f.r#type()),
            ("shear_stress", 3, Label::Repeated, Type::Double)
        );
    }
}
