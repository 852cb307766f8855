//! `hcs`: HCS telegrams (CMD 3 read, CMD 6 write, CMD 15 multi-write)
//! through the telegram channel of an HCS DMA-22(A) node (0x2000 request,
//! 0x2001 response), encoded and decoded by the `hcs-dma22` codec.

use crate::failure::{Failure, input};
use crate::output::outln;
use crate::target::{Session, Where};
use hcs_dma22::description::{
    map::{REQUEST, RESPONSE},
    od::MAX_TELEGRAM,
};
use hcs_dma22::telegram::{
    ModuleOutput, MultiWriteRequest, ReadRequest, RequestRepr, ResponseRepr, WriteParameter,
};
use master_test::cli;
use master_test::mailbox::{ClientError, MailboxClient};

const NO_CHANNEL: &str = "the node has no HCS telegram channel (0x2000/0x2001)";

/// Options of `hcs`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    #[command(subcommand)]
    op: Op,
}

/// `hcs` subcommands.
#[derive(clap::Subcommand, Debug, Clone)]
pub enum Op {
    /// CMD 3: read 1..=8 parameter words of a module, from ID onwards.
    Read {
        /// Module address (E22), 1..=5.
        #[arg(long, default_value_t = 1)]
        module: u8,
        /// Parameter ID (chapter 7), decimal or 0x-hex: 0x07 is d1.07.
        id: String,
        /// Number of words, 1..=8.
        #[arg(long, default_value_t = 1)]
        words: u16,
    },
    /// CMD 6: write one parameter of a module (the node answers with the
    /// request, or an exception).
    Write {
        /// Module address (E22), 1..=5.
        #[arg(long, default_value_t = 1)]
        module: u8,
        /// Parameter ID, decimal or 0x-hex: 0x1F is A1.01.
        id: String,
        /// The value, -32768..=65535 (negative for signed parameters).
        #[arg(allow_hyphen_values = true)]
        value: String,
    },
    /// CMD 15: process values for modules 1..=N (the node answers with
    /// the next module's status word and values).
    Multi {
        /// Process value 1 of each module, comma-separated: 1000,2000,-3000.
        #[arg(long, allow_hyphen_values = true)]
        values: String,
        /// Process value 2 of each module (default 0).
        #[arg(long, allow_hyphen_values = true)]
        values2: Option<String>,
        /// Control byte for every module (0x80 BUS_DISABLE).
        #[arg(long, default_value = "0")]
        control: String,
    },
    /// Send a telegram given as hex bytes (`24 01 03 00 07 00 01`) and
    /// print the answer's bytes.
    Raw {
        /// The telegram bytes, hex, spaces optional.
        #[arg(num_args = 1.., allow_hyphen_values = true)]
        bytes: Vec<String>,
    },
}

fn number(what: &str, s: &str, min: i128, max: i128) -> Result<i128, Failure> {
    let v = cli::parse_int(s).ok_or_else(|| {
        input(format!(
            "{what} '{s}' is not a number (decimal, or hex with 0x)"
        ))
    })?;
    if v < min || v > max {
        return Err(input(format!("{what} {v} is outside {min}..={max}")));
    }
    Ok(v)
}

fn list(what: &str, s: &str) -> Result<Vec<i16>, Failure> {
    s.split(',')
        .map(|v| number(what, v.trim(), -32768, 32767).map(|v| v as i16))
        .collect()
}

fn hex_bytes(parts: &[String]) -> Result<Vec<u8>, Failure> {
    let text: String = parts
        .concat()
        .chars()
        .filter(|c| !c.is_whitespace())
        .collect();
    let text = text.trim_start_matches("0x");
    if !text.is_ascii()
        || text.is_empty()
        || !text.len().is_multiple_of(2)
        || text.len() / 2 > MAX_TELEGRAM
    {
        return Err(input(format!(
            "a telegram is 1..={MAX_TELEGRAM} bytes in hex (two digits each)"
        )));
    }
    (0..text.len())
        .step_by(2)
        .map(|i| {
            u8::from_str_radix(&text[i..i + 2], 16)
                .map_err(|_| input(format!("'{}' is not a hex byte", &text[i..i + 2])))
        })
        .collect()
}

/// An SDO failure on the channel objects; "object does not exist" means
/// the device has no channel.
fn channel_error(e: ClientError) -> Failure {
    let missing = e.abort_code() == Some(0x0602_0000);
    let f = Failure::from(e);
    if missing { f.context(NO_CHANNEL) } else { f }
}

/// The TADR of the last request in the channel, so that a new one differs
/// (the node answers only a changed request, 3.3).
async fn last_tadr(c: &mut MailboxClient<'_>) -> Result<u8, Failure> {
    let len = c
        .sdo_upload(REQUEST, 1, false)
        .await
        .map_err(channel_error)?;
    if len.first().copied().unwrap_or(0) == 0 {
        return Ok(0);
    }
    Ok(c.sdo_upload(REQUEST, 2, false)
        .await?
        .first()
        .copied()
        .unwrap_or(0))
}

/// Writes `telegram` into 0x2000 (complete access from subindex 1: length
/// and bytes) and reads the answer from 0x2001.
async fn exchange(c: &mut MailboxClient<'_>, telegram: &[u8]) -> Result<Vec<u8>, Failure> {
    let mut data = vec![telegram.len() as u8];
    data.extend_from_slice(telegram);
    data.resize(1 + MAX_TELEGRAM, 0);
    c.sdo_download(REQUEST, 1, true, &data)
        .await
        .map_err(channel_error)?;
    let answer = c
        .sdo_upload(RESPONSE, 1, true)
        .await
        .map_err(channel_error)?;
    let n = usize::from(answer.first().copied().unwrap_or(0)).min(MAX_TELEGRAM);
    Ok(answer.get(1..1 + n).unwrap_or(&[]).to_vec())
}

/// Prints a decoded answer; an exception is a refusal (exit 1).
fn show(answer: &[u8]) -> Result<(), Failure> {
    if answer.is_empty() {
        outln!(
            "no answer (the node answers only a request that differs from the previous one, \
             and ignores a telegram it cannot read)"
        );
        return Ok(());
    }
    match ResponseRepr::parse(answer) {
        Ok(ResponseRepr::Read(r)) => {
            for (k, w) in r.words().iter().enumerate() {
                outln!(
                    "module {}: word {k}: {} (0x{w:04X}, signed {})",
                    r.sadr,
                    w,
                    *w as i16
                );
            }
            Ok(())
        }
        Ok(ResponseRepr::Write(w)) => {
            outln!(
                "module {}: ID 0x{:04X} written: {} (0x{:04X})",
                w.sadr,
                w.id,
                w.value as i16,
                w.value
            );
            Ok(())
        }
        Ok(ResponseRepr::MultiWrite(m)) => {
            outln!(
                "module {}: status 0x{:04X}, value 1 {}, value 2 {}",
                m.sadr,
                m.status,
                m.value1,
                m.value2
            );
            Ok(())
        }
        Ok(ResponseRepr::Error(e)) => Err(Failure::Refused(format!(
            "module {}: {}",
            e.sadr, e.exception
        ))),
        Err(e) => Err(Failure::Mismatch(format!(
            "the answer {} is not an HCS telegram: {e}",
            cli::hex(answer)
        ))),
    }
}

/// Runs an `hcs` subcommand.
pub async fn run(w: &Where, args: Args) -> Result<(), Failure> {
    let op = args.op;
    // Everything is checked before anything is sent.
    let build = |tadr: u8| -> Result<Option<RequestRepr>, Failure> {
        Ok(Some(match &op {
            Op::Read { module, id, words } => {
                let r = ReadRequest {
                    tadr,
                    sadr: *module,
                    id: number("ID", id, 0, 0xFFFF)? as u16,
                    words: *words,
                };
                r.check().map_err(|e| input(format!("CMD 3: {e}")))?;
                RequestRepr::Read(r)
            }
            Op::Write { module, id, value } => RequestRepr::Write(WriteParameter {
                tadr,
                sadr: *module,
                id: number("ID", id, 0, 0xFFFF)? as u16,
                value: number("value", value, -32768, 65535)? as u16,
            }),
            Op::Multi {
                values,
                values2,
                control,
            } => {
                let v1 = list("value", values)?;
                let v2 = match values2 {
                    Some(s) => list("value 2", s)?,
                    None => vec![0; v1.len()],
                };
                if v1.len() != v2.len() {
                    return Err(input("--values and --values2 must name the same modules"));
                }
                let control = number("control byte", control, 0, 255)? as u8;
                let modules: Vec<ModuleOutput> = v1
                    .iter()
                    .zip(&v2)
                    .map(|(a, b)| ModuleOutput {
                        control,
                        value1: *a,
                        value2: *b,
                    })
                    .collect();
                RequestRepr::MultiWrite(
                    MultiWriteRequest::new(tadr, &modules)
                        .map_err(|e| input(format!("CMD 15: {e}")))?,
                )
            }
            Op::Raw { .. } => return Ok(None),
        }))
    };
    build(0)?;
    let raw = match &op {
        Op::Raw { bytes } => Some(hex_bytes(bytes)?),
        _ => None,
    };
    let s = Session::open(w).await?;
    let sel = s.select(w).await?;
    let mut c = s.client(&sel)?;
    let telegram = match raw {
        Some(b) => b,
        None => {
            let tadr = last_tadr(&mut c).await?.wrapping_add(1);
            let Some(req) = build(tadr)? else {
                return Err(input("nothing to send"));
            };
            let mut buf = vec![0u8; req.buffer_len()];
            req.emit(&mut buf)
                .map_err(|e| input(format!("cannot encode the telegram: {e}")))?;
            buf
        }
    };
    outln!("request  {}", cli::hex(&telegram));
    let answer = exchange(&mut c, &telegram).await?;
    outln!("response {}", cli::hex(&answer));
    show(&answer)
}
