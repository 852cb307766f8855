//! CoE mailbox round trips through ethercrab on the virtual link, one
//! PAM-199 slave in PRE-OP (real-time clock, the link thread running):
//!
//! * `upload/ethercrab_sdo_read_u32`: expedited upload of 0x1018:02
//!   PRODUCT CODE with ethercrab's own `SubDeviceRef::sdo_read::<u32>`;
//! * `upload/mailbox_client`: the same upload through this crate's
//!   `MailboxClient::sdo_upload`;
//! * `download_86_bytes/*`: complete-access download of the 86-byte curve
//!   object 0x8006 (subindex 0 + 42 x INT): `sdo_download_with(.., true)`,
//!   which with a 128-byte mailbox still fits all 86 bytes into the
//!   initiate request (one normal transfer, one mailbox exchange), and a
//!   truly segmented download (initiate without data, then one download
//!   segment carrying the 86 bytes: two exchanges).
//!
//! ethercrab's upload runs on a bus of its own and the client's transfers
//! on a second one: the two count mailbox messages independently, and a
//! slave drops a message whose counter repeats the previous one.
//!
//! Run: `cargo bench -p master-test --bench coe`. Criterion reports the
//! time per round trip (per transfer) and, for the downloads, bytes/s.
//! Each iteration batch runs inside one `smol::block_on` (`iter_custom`),
//! so executor start-up is not measured.

// criterion's group macro generates an undocumented function.
#![allow(missing_docs)]

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use ecat_slave::wire::coe::{CoeHeader, CoeService, DownloadKind, SdoRequest, SdoResponse};
use ecat_slave::wire::mailbox::MailboxType;
use master_test::VirtualBus;
use master_test::mailbox::{ClientError, MailboxClient, MailboxGeometry};
use std::hint::black_box;
use std::time::{Duration, Instant};

/// Starts a segmented complete-access download of `data` into `index`
/// (initiate request with no data) and sends all of it as segments.
async fn segmented_ca_download(
    c: &mut MailboxClient<'_>,
    index: u16,
    data: &[u8],
) -> Result<(), ClientError> {
    let req = SdoRequest::InitiateDownload {
        index,
        sub: 0,
        complete_access: true,
        kind: DownloadKind::Normal {
            complete_size: data.len() as u32,
            data: &[],
        },
    };
    let mut payload = vec![0u8; CoeHeader::<&[u8]>::HEADER_LEN + req.buffer_len()];
    CoeHeader::emit_into(&mut payload[..2], 0, CoeService::SdoRequest);
    req.emit(&mut payload[2..])
        .map_err(|e| ClientError::Protocol(e.to_string()))?;
    c.send(MailboxType::CoE, &payload).await?;
    loop {
        let msg = c.receive().await?;
        let coe = CoeHeader::new_checked(&msg.payload[..])
            .map_err(|e| ClientError::Protocol(e.to_string()))?;
        if msg.kind != MailboxType::CoE || coe.service() != CoeService::SdoResponse {
            continue; // an emergency, not the answer
        }
        match SdoResponse::parse(&msg.payload[2..]) {
            Ok(SdoResponse::InitiateDownloadAck { .. }) => break,
            other => return Err(ClientError::Protocol(format!("{other:?}"))),
        }
    }
    let room = usize::from(MailboxGeometry::standard().out.1) - 6 - 2 - 1;
    let mut sent = 0;
    let mut toggle = false;
    while sent < data.len() {
        let n = (data.len() - sent).min(room);
        c.download_segment(toggle, sent + n == data.len(), &data[sent..sent + n])
            .await?;
        sent += n;
        toggle = !toggle;
    }
    Ok(())
}

/// (a) ethercrab's own expedited upload. A bus of its own: ethercrab and
/// [`MailboxClient`] count mailbox messages independently, and a slave
/// ignores a message whose counter repeats the previous one.
fn ethercrab_upload(c: &mut Criterion) {
    let bus = VirtualBus::new(1).expect("virtual bus");
    let md = &*bus.maindevice;
    let group = smol::block_on(bus.init()).expect("PRE-OP");
    let sd = group.subdevice(md, 0).expect("one slave");
    let mut g = c.benchmark_group("upload");
    g.measurement_time(Duration::from_secs(3)).sample_size(20);
    g.bench_function("ethercrab_sdo_read_u32", |b| {
        b.iter_custom(|iters| {
            smol::block_on(async {
                let t = Instant::now();
                for _ in 0..iters {
                    let v: u32 = sd.sdo_read(0x1018, 2).await.expect("sdo_read");
                    black_box(v);
                }
                t.elapsed()
            })
        })
    });
    g.finish();
}

/// (b) the same upload and (c) the 86-byte downloads with [`MailboxClient`].
fn client_transfers(c: &mut Criterion) {
    let bus = VirtualBus::new(1).expect("virtual bus");
    let md = &*bus.maindevice;
    let group = smol::block_on(bus.init()).expect("PRE-OP");
    let station = group
        .subdevice(md, 0)
        .expect("one slave")
        .configured_address();
    let mut client = MailboxClient::new(md, station, MailboxGeometry::standard());
    let image = smol::block_on(client.sdo_upload(0x8006, 0, true)).expect("curve image");
    assert_eq!(image.len(), 86);

    let mut g = c.benchmark_group("upload");
    g.measurement_time(Duration::from_secs(3)).sample_size(20);
    g.bench_function("mailbox_client", |b| {
        b.iter_custom(|iters| {
            smol::block_on(async {
                let t = Instant::now();
                for _ in 0..iters {
                    let v = client.sdo_upload(0x1018, 2, false).await.expect("upload");
                    black_box(v);
                }
                t.elapsed()
            })
        })
    });
    g.finish();

    let mut g = c.benchmark_group("download_86_bytes");
    g.measurement_time(Duration::from_secs(3))
        .sample_size(20)
        .throughput(Throughput::Bytes(image.len() as u64));
    g.bench_function("sdo_download_with_forced", |b| {
        b.iter_custom(|iters| {
            smol::block_on(async {
                let t = Instant::now();
                for _ in 0..iters {
                    client
                        .sdo_download_with(0x8006, 0, true, black_box(&image), true)
                        .await
                        .expect("download");
                }
                t.elapsed()
            })
        })
    });
    g.bench_function("segmented", |b| {
        b.iter_custom(|iters| {
            smol::block_on(async {
                let t = Instant::now();
                for _ in 0..iters {
                    segmented_ca_download(&mut client, 0x8006, black_box(&image))
                        .await
                        .expect("segmented download");
                }
                t.elapsed()
            })
        })
    });
    g.finish();

    // The curve is unchanged after all those downloads.
    let after = smol::block_on(client.sdo_upload(0x8006, 0, true)).expect("read back");
    assert_eq!(after, image);
}

criterion_group!(benches, ethercrab_upload, client_transfers);
criterion_main!(benches);
