//! GRBL 1.1 status codes the parser returns (`error:N`).

pub const EXPECTED_COMMAND_LETTER: u8 = 1;
pub const BAD_NUMBER_FORMAT: u8 = 2;
pub const NEGATIVE_VALUE: u8 = 4;
pub const UNSUPPORTED_COMMAND: u8 = 20;
pub const MODAL_GROUP_VIOLATION: u8 = 21;
pub const UNDEFINED_FEED_RATE: u8 = 22;
pub const COMMAND_VALUE_NOT_INTEGER: u8 = 23;
pub const AXIS_COMMAND_CONFLICT: u8 = 24;
pub const WORD_REPEATED: u8 = 25;
pub const NO_AXIS_WORDS: u8 = 26;
pub const INVALID_LINE_NUMBER: u8 = 27;
pub const VALUE_WORD_MISSING: u8 = 28;
pub const UNSUPPORTED_COORD_SYS: u8 = 29;
pub const G53_INVALID_MOTION_MODE: u8 = 30;
pub const AXIS_WORDS_EXIST: u8 = 31;
pub const NO_AXIS_WORDS_IN_PLANE: u8 = 32;
pub const INVALID_TARGET: u8 = 33;
pub const ARC_RADIUS_ERROR: u8 = 34;
pub const NO_OFFSETS_IN_PLANE: u8 = 35;
pub const UNUSED_WORDS: u8 = 36;
pub const MAX_VALUE_EXCEEDED: u8 = 38;
