//! The runner's answers ahead ([`Chain::ahead`]): while it waits for the
//! next frame, the reply to the last process-data frame's shape is worked
//! out (the firmware has just run, so the line's state is in the caches);
//! a frame of that shape is answered at once and then run through the
//! ESCs as always, whose reply must be the one sent.

use crate::chain::{Ahead, Chain};
use ecat_slave::wire::ecat::{Addressing, Datagram, DatagramCursor, EcatFrame};
use ecat_slave::wire::ethernet::EthernetFrame;

/// What the runner worked out ahead, and how it went.
#[derive(Debug)]
pub(super) struct AheadAnswers {
    /// Off by configuration, or after a difference.
    enabled: bool,
    /// The last process-data request answered the normal way (empty:
    /// none yet).
    template: Vec<u8>,
    /// Whether `prepared` was worked out since the line last changed.
    worked_out: bool,
    prepared: Option<Ahead>,
    /// The reply sent ahead.
    reply: Vec<u8>,
    /// Frames answered ahead.
    pub(super) answered: u64,
    /// Frames whose reply from the ESCs differed from the one sent ahead.
    pub(super) differed: u64,
}

impl AheadAnswers {
    pub(super) fn new(enabled: bool) -> Self {
        Self {
            enabled,
            template: Vec::new(),
            worked_out: false,
            prepared: None,
            reply: Vec::new(),
            answered: 0,
            differed: 0,
        }
    }

    /// Something ran on the line (a frame, the firmware, a link change):
    /// what was worked out no longer holds.
    pub(super) fn forget(&mut self) {
        self.prepared = None;
        self.worked_out = false;
    }

    /// Before waiting for a frame: works out the reply to the last
    /// process-data frame's shape, once per change of the line.
    pub(super) fn prepare(&mut self, chain: &Chain) {
        if self.enabled && !self.worked_out && !self.template.is_empty() {
            self.prepared = chain.ahead(&self.template);
            self.worked_out = true;
        }
    }

    /// The reply to `request`, which entered the line at `now_ns`, if it
    /// has the shape worked out for. What was worked out is used up either
    /// way (the frame changes the line).
    pub(super) fn answer(&mut self, request: &[u8], now_ns: u64) -> Option<&mut [u8]> {
        let ahead = self.prepared.take();
        self.worked_out = false;
        let ahead = ahead?;
        self.reply.clear();
        self.reply.extend_from_slice(request);
        if !ahead.answer(&mut self.reply, now_ns) {
            return None;
        }
        self.answered += 1;
        Some(&mut self.reply)
    }

    /// A request about to be answered the normal way: one carrying
    /// process data (a logical datagram) is the shape to work out next.
    pub(super) fn learn(&mut self, request: &[u8]) {
        if self.enabled && carries_process_data(request) {
            self.template.clear();
            self.template.extend_from_slice(request);
        }
    }

    /// The ESCs' own reply to the frame answered ahead. A difference would
    /// be a bug: it is counted, and nothing is answered ahead any more in
    /// this run. Returns whether the replies are the same.
    pub(super) fn check(&mut self, processed: &[u8]) -> bool {
        if processed == self.reply.as_slice() {
            return true;
        }
        self.differed += 1;
        self.enabled = false;
        self.forget();
        false
    }
}

/// Whether an EtherCAT frame holds a logical datagram.
fn carries_process_data(frame: &[u8]) -> bool {
    let Ok(eth) = EthernetFrame::new_checked(frame) else {
        return false;
    };
    let Ok(ecat) = EcatFrame::new_checked(eth.payload()) else {
        return false;
    };
    let payload = ecat.payload();
    let mut cursor = DatagramCursor::new();
    while let Some(Ok(range)) = cursor.next_range(payload) {
        if let Some(Ok(dg)) = payload.get(range).map(Datagram::new_checked)
            && dg.command().addressing() == Addressing::Logical
        {
            return true;
        }
    }
    false
}

#[cfg(test)]
mod tests {
    use super::*;
    use ecat_slave::wire::ecat::Command;

    use crate::testing::one_datagram as frame;

    /// A line of one slave with 4 output bytes at logical 0 (into 0x1100),
    /// one cycle run.
    fn line() -> Chain {
        let mut line = crate::testing::line(1);
        let f = crate::testing::fmmu(0, 4, 0x1100, 2);
        line.process_frame(&mut frame(Command::Apwr, 0x0600 << 16, &f));
        line.process_frame(&mut frame(Command::Lwr, 0, &[0; 4]));
        line
    }

    #[test]
    fn the_shape_of_the_last_process_data_frame_is_answered_until_the_line_changes() {
        let mut line = line();
        let mut answers = AheadAnswers::new(true);
        // Nothing learnt yet.
        answers.prepare(&line);
        assert!(
            answers
                .answer(&frame(Command::Lwr, 0, &[1; 4]), 0)
                .is_none()
        );
        // A status read is no template; the cyclic frame is.
        answers.learn(&frame(Command::Brd, 0x0130 << 16, &[0; 2]));
        answers.prepare(&line);
        assert!(
            answers
                .answer(&frame(Command::Lwr, 0, &[1; 4]), 0)
                .is_none()
        );
        let request = frame(Command::Lwr, 0, &[1; 4]);
        answers.learn(&request);
        answers.prepare(&line);
        let sent = answers
            .answer(&request, 0)
            .expect("answered ahead")
            .to_vec();
        let mut processed = request.clone();
        line.process_frame(&mut processed);
        assert_eq!(sent, processed);
        assert!(answers.check(&processed));
        // Used up by the frame: worked out again before the next.
        assert!(answers.answer(&request, 0).is_none());
        answers.prepare(&line);
        answers.forget();
        assert!(answers.answer(&request, 0).is_none());
        answers.prepare(&line);
        assert!(answers.answer(&request, 0).is_some());
        assert_eq!((answers.answered, answers.differed), (2, 0));
    }

    /// The cyclic frame of a one-slave line (LWR of 4 bytes at logical
    /// `at`, FPRD of the AL status at station 0x1000) answered ahead over
    /// several cycles, the line changed in between by `change`: every
    /// reply sent ahead must be the ESC's own.
    fn answered_ahead_across(at: u32, change: &[u8]) {
        use ecat_slave::wire::builder::FrameBuilder;
        let mut line = line();
        line.process_frame(&mut frame(
            Command::Apwr,
            0x0010 << 16,
            &0x1000u16.to_le_bytes(),
        ));
        let mut buf = vec![0u8; 200];
        let mut fb = FrameBuilder::new(&mut buf, [0x10; 6]).unwrap();
        fb.push(Command::Lwr, at, &[1; 4]).unwrap();
        fb.push(Command::Fprd, 0x1000 | (0x0130 << 16), &[0; 2])
            .unwrap();
        let len = fb.finish();
        let request = buf[..len].to_vec();
        let mut answers = AheadAnswers::new(true);
        answers.learn(&request);
        for cycle in 0..4 {
            if cycle == 2 {
                line.process_frame(&mut change.to_vec());
                answers.forget();
                answers.learn(&request);
            }
            answers.prepare(&line);
            let sent = answers.answer(&request, 0).map(|r| r.to_vec());
            let mut processed = request.clone();
            line.process_frame(&mut processed);
            if let Some(sent) = sent {
                assert_eq!(sent, processed, "cycle {cycle}");
                assert!(answers.check(&processed), "cycle {cycle}");
            }
        }
        assert_eq!(answers.differed, 0);
        assert!(answers.answered >= 2, "answered {}", answers.answered);
    }

    #[test]
    fn a_one_slave_line_remapped_or_readdressed_is_answered_as_its_esc_answers() {
        // The FMMU moved away from logical 0, where the LWR goes, and to
        // logical 0x100, where it goes: the window index must follow.
        for at in [0, 0x100] {
            answered_ahead_across(
                at,
                &frame(
                    Command::Apwr,
                    0x0600 << 16,
                    &crate::testing::fmmu(0x100, 4, 0x1100, 2),
                ),
            );
        }
        // The station address changed: the FPRD no longer reaches it (the
        // address index must follow).
        answered_ahead_across(
            0,
            &frame(Command::Apwr, 0x0010 << 16, &0x2000u16.to_le_bytes()),
        );
    }

    #[test]
    fn a_reply_that_differs_switches_answering_ahead_off() {
        let line = line();
        let mut answers = AheadAnswers::new(true);
        let request = frame(Command::Lwr, 0, &[1; 4]);
        answers.learn(&request);
        answers.prepare(&line);
        assert!(answers.answer(&request, 0).is_some());
        assert!(!answers.check(&request));
        assert_eq!(answers.differed, 1);
        answers.prepare(&line);
        assert!(answers.answer(&request, 0).is_none());
    }

    #[test]
    fn switched_off_it_answers_nothing() {
        let line = line();
        let mut answers = AheadAnswers::new(false);
        let request = frame(Command::Lwr, 0, &[1; 4]);
        answers.learn(&request);
        answers.prepare(&line);
        assert!(answers.answer(&request, 0).is_none());
    }

    #[test]
    fn any_bytes_are_no_process_data_frame_or_a_logical_one() {
        assert!(!carries_process_data(&[]));
        assert!(!carries_process_data(&[0xff; 64]));
        assert!(carries_process_data(&frame(Command::Lrw, 0, &[0; 4])));
        assert!(!carries_process_data(&frame(Command::Fprd, 0, &[0; 4])));
    }
}
