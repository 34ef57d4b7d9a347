//! Bus nodes, legs and drives.

/// A node on the robot's CAN bus. Carried on the wire as one byte.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum NodeId {
    /// The controller firmware.
    Controller = 1,
    /// Leg drive of the front-left leg.
    LegDriveFl = 2,
    /// Leg drive of the front-right leg.
    LegDriveFr = 3,
    /// Leg drive of the back-left leg.
    LegDriveBl = 4,
    /// Leg drive of the back-right leg.
    LegDriveBr = 5,
    /// Drive of both wheels.
    WheelDrive = 6,
    /// Torso IMU.
    Imu = 7,
    /// Operator teleop program.
    Teleop = 8,
    /// The simulator's clock (SYNC).
    Simulator = 9,
    /// A tool outside the system, e.g. `cansend` run by an operator.
    Tool = 10,
    /// The rangefinder looking at the ground behind the torso.
    Rangefinder = 11,
}

impl NodeId {
    /// Every node, in id order.
    pub const ALL: [NodeId; 11] = [
        NodeId::Controller,
        NodeId::LegDriveFl,
        NodeId::LegDriveFr,
        NodeId::LegDriveBl,
        NodeId::LegDriveBr,
        NodeId::WheelDrive,
        NodeId::Imu,
        NodeId::Teleop,
        NodeId::Simulator,
        NodeId::Tool,
        NodeId::Rangefinder,
    ];

    /// The node with this raw id, or `None` if no node has it.
    pub const fn new(raw: u8) -> Option<NodeId> {
        Some(match raw {
            1 => NodeId::Controller,
            2 => NodeId::LegDriveFl,
            3 => NodeId::LegDriveFr,
            4 => NodeId::LegDriveBl,
            5 => NodeId::LegDriveBr,
            6 => NodeId::WheelDrive,
            7 => NodeId::Imu,
            8 => NodeId::Teleop,
            9 => NodeId::Simulator,
            10 => NodeId::Tool,
            11 => NodeId::Rangefinder,
            _ => return None,
        })
    }

    /// Name as it appears in the DBC (`BU_`).
    pub const fn name(self) -> &'static str {
        match self {
            NodeId::Controller => "Controller",
            NodeId::LegDriveFl => "LegDrive_FL",
            NodeId::LegDriveFr => "LegDrive_FR",
            NodeId::LegDriveBl => "LegDrive_BL",
            NodeId::LegDriveBr => "LegDrive_BR",
            NodeId::WheelDrive => "WheelDrive",
            NodeId::Imu => "Imu",
            NodeId::Teleop => "Teleop",
            NodeId::Simulator => "Simulator",
            NodeId::Tool => "Tool",
            NodeId::Rangefinder => "Rangefinder",
        }
    }
}

/// One of the four legs. Joint index `leg as usize * 4 + joint` orders the 16 joints.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[repr(u8)]
pub enum Leg {
    /// Front left.
    Fl = 0,
    /// Front right.
    Fr = 1,
    /// Back left.
    Bl = 2,
    /// Back right.
    Br = 3,
}

impl Leg {
    /// The four legs in joint-index order.
    pub const ALL: [Leg; 4] = [Leg::Fl, Leg::Fr, Leg::Bl, Leg::Br];

    /// Whether this is a front leg.
    pub const fn is_front(self) -> bool {
        matches!(self, Leg::Fl | Leg::Fr)
    }

    /// Suffix used by the report's joint names (`hip1_fl`).
    pub const fn suffix(self) -> &'static str {
        match self {
            Leg::Fl => "fl",
            Leg::Fr => "fr",
            Leg::Bl => "bl",
            Leg::Br => "br",
        }
    }

    /// The drive that serves this leg.
    pub const fn drive(self) -> Drive {
        match self {
            Leg::Fl => Drive::LegFl,
            Leg::Fr => Drive::LegFr,
            Leg::Bl => Drive::LegBl,
            Leg::Br => Drive::LegBr,
        }
    }
}

/// A motor drive: one per leg and one for both wheels.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum Drive {
    /// Front-left leg drive.
    LegFl = 0,
    /// Front-right leg drive.
    LegFr = 1,
    /// Back-left leg drive.
    LegBl = 2,
    /// Back-right leg drive.
    LegBr = 3,
    /// Wheel drive.
    Wheel = 4,
}

impl Drive {
    /// Every drive, in id order.
    pub const ALL: [Drive; 5] = [
        Drive::LegFl,
        Drive::LegFr,
        Drive::LegBl,
        Drive::LegBr,
        Drive::Wheel,
    ];

    /// The bus node of this drive.
    pub const fn node(self) -> NodeId {
        match self {
            Drive::LegFl => NodeId::LegDriveFl,
            Drive::LegFr => NodeId::LegDriveFr,
            Drive::LegBl => NodeId::LegDriveBl,
            Drive::LegBr => NodeId::LegDriveBr,
            Drive::Wheel => NodeId::WheelDrive,
        }
    }
}

/// The report's 16 leg joint names, in joint-index order (leg-major: FL, FR, BL, BR; within a
/// leg hip abduction `hip1`, hip pitch `hip2`, knee, ankle).
pub const JOINT_NAMES: [&str; 16] = [
    "hip1_fl", "hip2_fl", "knee_fl", "ankle_fl", "hip1_fr", "hip2_fr", "knee_fr", "ankle_fr",
    "hip1_bl", "hip2_bl", "knee_bl", "ankle_bl", "hip1_br", "hip2_br", "knee_br", "ankle_br",
];

/// Joint names within one leg, in order.
pub const LEG_JOINT_NAMES: [&str; 4] = ["hip1", "hip2", "knee", "ankle"];

/// Wheel names, in order (left, right).
pub const WHEEL_NAMES: [&str; 2] = ["left", "right"];

impl serde::Serialize for NodeId {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_u8(*self as u8)
    }
}

impl<'de> serde::Deserialize<'de> for NodeId {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let raw = <u8 as serde::Deserialize>::deserialize(deserializer)?;
        NodeId::new(raw).ok_or_else(|| serde::de::Error::custom("unknown node id"))
    }
}

impl postcard::experimental::max_size::MaxSize for NodeId {
    const POSTCARD_MAX_SIZE: usize = 1;
}

impl crate::signal::WireField for NodeId {
    const TYPE: crate::signal::WireType = crate::signal::WireType::U8;
    const EXP10: i8 = 0;
    const UNIT: &'static str = "";
    const RAW_MIN: i64 = 1;
    const RAW_MAX: i64 = 11;
    const VALUES: &'static [(u32, &'static str)] = &[
        (1, "Controller"),
        (2, "LegDrive_FL"),
        (3, "LegDrive_FR"),
        (4, "LegDrive_BL"),
        (5, "LegDrive_BR"),
        (6, "WheelDrive"),
        (7, "Imu"),
        (8, "Teleop"),
        (9, "Simulator"),
        (10, "Tool"),
        (11, "Rangefinder"),
    ];
}
