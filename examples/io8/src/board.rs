//! The IO8's hardware, as the application sees it: eight input pins and
//! eight output drivers. A real board implements [`Board`] on its GPIO
//! registers; [`SimBoard`] stands in for it in tests and software slaves.

/// The device's hardware abstraction: what the application reads and
/// drives. Bit n is channel n + 1.
pub trait Board {
    /// The input levels now (bit n: input n + 1 is high), unfiltered.
    fn inputs(&mut self) -> u8;

    /// Drives the outputs (bit n: output n + 1 on).
    fn set_outputs(&mut self, bits: u8);
}

/// A simulated board: the test (or the simulation around a software slave)
/// sets the input levels and reads what the firmware drives.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SimBoard {
    /// Input levels the firmware reads (bit n: input n + 1 high).
    pub input_levels: u8,
    /// Output levels the firmware last drove (bit n: output n + 1 on).
    pub output_levels: u8,
    /// How many times the firmware drove the outputs.
    pub output_writes: u32,
}

impl SimBoard {
    /// A board with every input low and every output off.
    pub const fn new() -> Self {
        SimBoard {
            input_levels: 0,
            output_levels: 0,
            output_writes: 0,
        }
    }

    /// Sets input `channel` (1..=8) high or low; other channels are ignored.
    pub fn set_input(&mut self, channel: u8, high: bool) {
        let Some(mask) = channel_mask(channel) else {
            return;
        };
        if high {
            self.input_levels |= mask;
        } else {
            self.input_levels &= !mask;
        }
    }

    /// Whether output `channel` (1..=8) is driven on.
    pub fn output(&self, channel: u8) -> bool {
        channel_mask(channel).is_some_and(|m| self.output_levels & m != 0)
    }
}

/// The bit of channel 1..=8.
fn channel_mask(channel: u8) -> Option<u8> {
    (1..=8).contains(&channel).then(|| 1 << (channel - 1))
}

impl Board for SimBoard {
    fn inputs(&mut self) -> u8 {
        self.input_levels
    }

    fn set_outputs(&mut self, bits: u8) {
        self.output_levels = bits;
        self.output_writes = self.output_writes.saturating_add(1);
    }
}
