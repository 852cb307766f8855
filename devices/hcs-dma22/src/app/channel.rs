//! The HCS telegram channel over CoE: the node answers the telegrams of
//! the HCS fieldbus protocol (CMD 3 read, CMD 6 write, CMD 15 multi-write,
//! 000 chapters 4 and 5) written into a CoE object, so tools that speak
//! HCS telegrams reach the modules' parameters over EtherCAT.
//!
//! - 0x2000 *HCS telegram request* (RW): sub 1 the telegram's length, subs
//!   2..=33 its bytes. Writing sub 1 (alone, or in a complete access from
//!   sub 1 with the bytes) hands the telegram to the node.
//! - 0x2001 *HCS telegram response* (RO): sub 1 the answer's length (0: no
//!   answer, as the node gives none to an unchanged request, 3.3), subs
//!   2..=33 its bytes.
//!
//! The node's rules apply: an unchanged request is not answered (change
//! TADR to force an answer), CMD 15 answers come from modules 1..=SNUM in
//! turn, a module that is not plugged answers exception 5 (CMD 3 / CMD 6)
//! or 8 (CMD 15); an unknown ID exception 2; a value outside the
//! parameter's range, CMD 6 exception 3; a read-only parameter, CMD 6
//! exception 4. Over EtherCAT the cyclic process data of OP take the
//! place of CMD 15: a CMD 15 through this channel writes the same
//! parameters (which the next cycle in OP overwrites).

use ecat_slave::od::Od;

use crate::telegram::semantics::{Multiplexer, ResponseGate};
use crate::telegram::{
    ErrorReply, Exception, MultiWriteException, MultiWriteResponse, ReadException, ReadResponse,
    RequestRepr, ResponseRepr, WriteException,
};

use super::model::{self, Module};
use crate::description::map::{INPUTS, REQUEST, RESPONSE, parameter, slot_index};
use crate::description::od::MAX_TELEGRAM;

/// The node's telegram state: the TADR rule and the CMD 15 multiplexer.
#[derive(Debug, Clone, Copy, Default)]
pub struct Channel {
    gate: ResponseGate,
    mux: Multiplexer,
}

/// The modules as the channel sees them.
pub struct Modules<'a> {
    /// Plugged modules, slot order.
    pub modules: &'a mut [Module],
    /// Their operation modes.
    pub modes: &'a [u8],
}

impl Channel {
    /// A channel that has seen no telegram.
    pub const fn new() -> Self {
        Channel {
            gate: ResponseGate::new(),
            mux: Multiplexer::new(),
        }
    }

    /// Takes the request in 0x2000 and writes the answer into 0x2001.
    pub fn serve_od(&mut self, od: &mut Od, modules: Modules<'_>) {
        let len = od
            .get(REQUEST, 1)
            .unwrap_or(0)
            .clamp(0, MAX_TELEGRAM as i64) as usize;
        let mut request = [0u8; MAX_TELEGRAM];
        for (k, b) in request.iter_mut().enumerate().take(len) {
            *b = od.get(REQUEST, k as u8 + 2).unwrap_or(0) as u8;
        }
        let mut answer = [0u8; MAX_TELEGRAM];
        let n = self.serve(od, request.get(..len).unwrap_or(&[]), modules, &mut answer);
        od.set(RESPONSE, 1, n as i64);
        for (k, b) in answer.iter().enumerate() {
            od.set(RESPONSE, k as u8 + 2, if k < n { i64::from(*b) } else { 0 });
        }
    }

    /// Answers one telegram into `out`; returns the answer's length (0: no
    /// answer).
    pub fn serve(
        &mut self,
        od: &mut Od,
        request: &[u8],
        m: Modules<'_>,
        out: &mut [u8; MAX_TELEGRAM],
    ) -> usize {
        let plugged = m.modules.len().min(5) as u8;
        let req = match RequestRepr::parse(request) {
            Ok(r) => r,
            Err(e) => {
                // What can be answered: an exception the manual names for
                // this error, with the header the telegram carried; a CMD
                // 15 shorter than 3 + 5 x SNUM is the node's own exception
                // 9 (SADR 0, 5.3). Anything else is not answered, as the
                // node ignores a telegram it cannot read.
                let (Some(&tadr), Some(&sadr)) = (request.first(), request.get(1)) else {
                    return 0;
                };
                let short_cmd15 = request.get(2) == Some(&15)
                    && matches!(e, crate::telegram::TelegramError::Truncated { .. });
                let reply = match e.exception() {
                    Some(exception) => ErrorReply {
                        tadr,
                        sadr,
                        exception,
                    },
                    None if short_cmd15 => ErrorReply {
                        tadr,
                        sadr: 0,
                        exception: Exception::MultiWrite(MultiWriteException::DataLengthTooSmall),
                    },
                    None => return 0,
                };
                return emit(ResponseRepr::Error(reply), out);
            }
        };
        if !self.gate.admit(&req) {
            return 0;
        }
        let answer = match req {
            RequestRepr::Read(r) => {
                let fail = |x| {
                    ResponseRepr::Error(ErrorReply {
                        tadr: r.tadr,
                        sadr: r.sadr,
                        exception: Exception::Read(x),
                    })
                };
                if r.sadr == 0 || r.sadr > plugged {
                    fail(ReadException::SlaveTimeout)
                } else {
                    let slot = r.sadr - 1;
                    let mut words = [0u16; 8];
                    let mut bad = false;
                    for (k, w) in words.iter_mut().enumerate().take(usize::from(r.words)) {
                        match read(od, slot, r.id.wrapping_add(k as u16)) {
                            Some(v) => *w = v as u16,
                            None => bad = true,
                        }
                    }
                    if bad {
                        fail(ReadException::WrongId)
                    } else {
                        match ReadResponse::new(
                            r.tadr,
                            r.sadr,
                            words.get(..usize::from(r.words)).unwrap_or(&[]),
                        ) {
                            Ok(resp) => ResponseRepr::Read(resp),
                            Err(_) => fail(ReadException::CntOutOfRange),
                        }
                    }
                }
            }
            RequestRepr::Write(w) => {
                let fail = |x| {
                    ResponseRepr::Error(ErrorReply {
                        tadr: w.tadr,
                        sadr: w.sadr,
                        exception: Exception::Write(x),
                    })
                };
                if w.sadr == 0 || w.sadr > plugged {
                    fail(WriteException::SlaveTimeout)
                } else {
                    let slot = w.sadr - 1;
                    match write(od, slot, w.id, w.value) {
                        Ok(v) => {
                            if w.id == model::id::E_INT
                                && let Some(module) = m.modules.get_mut(usize::from(slot))
                            {
                                module.write_e_int(v as u16);
                            }
                            ResponseRepr::Write(w)
                        }
                        Err(x) => fail(x),
                    }
                }
            }
            RequestRepr::MultiWrite(mw) => {
                let snum = mw.snum();
                if snum > plugged {
                    // 5.3: the first module that is not installed answers
                    // exception 8.
                    ResponseRepr::Error(ErrorReply {
                        tadr: mw.tadr(),
                        sadr: plugged + 1,
                        exception: Exception::MultiWrite(MultiWriteException::SlaveTimeout),
                    })
                } else {
                    for (slot, block) in mw.modules().iter().enumerate() {
                        let s = slot as u8;
                        let mode = m.modes.get(slot).copied().unwrap_or(3);
                        let (t1, t2) = model::process_value_targets(mode);
                        model::set(od, s, t1, i64::from(block.value1).clamp(-9999, 9999));
                        model::set(od, s, t2, i64::from(block.value2).clamp(-9999, 9999));
                        if let Some(module) = m.modules.get_mut(slot) {
                            module.write_control(block.control);
                        }
                    }
                    let sadr = self.mux.next_sadr(snum).unwrap_or(1);
                    let i = slot_index(INPUTS, sadr - 1);
                    ResponseRepr::MultiWrite(MultiWriteResponse {
                        tadr: mw.tadr(),
                        sadr,
                        status: od.get(i, 1).unwrap_or(0) as u16,
                        value1: od.get(i, 2).unwrap_or(0) as i16,
                        value2: od.get(i, 3).unwrap_or(0) as i16,
                    })
                }
            }
        };
        emit(answer, out)
    }
}

fn emit(answer: ResponseRepr, out: &mut [u8; MAX_TELEGRAM]) -> usize {
    answer.emit(out).unwrap_or(0)
}

/// Parameter `id` of the module in `slot`, if it exists.
fn read(od: &Od, slot: u8, id: u16) -> Option<i64> {
    let (index, sub) = parameter(slot, id)?;
    od.get(index, sub)
}

/// Writes parameter `id` of the module in `slot` as CMD 6 does: the word
/// is signed where the parameter's range is; checks existence, access and
/// range. Returns the value written.
fn write(od: &mut Od, slot: u8, id: u16, word: u16) -> Result<i64, WriteException> {
    let (index, sub) = parameter(slot, id).ok_or(WriteException::WrongId)?;
    let (_, e) = od
        .dictionary()
        .find_entry(index, sub)
        .ok_or(WriteException::WrongId)?;
    if !e.access().writable() {
        return Err(WriteException::WriteFailed);
    }
    let v = if e.data_type.is_signed() {
        i64::from(word as i16)
    } else {
        i64::from(word)
    };
    if e.min().is_some_and(|min| v < min) || e.max().is_some_and(|max| v > max) {
        return Err(WriteException::WrongDataValue);
    }
    od.set(index, sub, v);
    Ok(v)
}
