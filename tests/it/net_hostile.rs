//! A hostile client against a server over renet's netcode UDP transport
//! on 127.0.0.1: bytes that are no request, coordinates outside the grid's
//! bit budget, NaN, a hull of a million points, a tool too large, an
//! unknown terrain and a flood of carves. Each is refused with its reason,
//! the server keeps serving, and an honest client's carves all apply, with
//! its terrain equal to the server's. A secure server admits only
//! clients with a connect token signed by its key.

use crate::{ONE_APP_AT_A_TIME, net};

use bevy::prelude::*;
use bevy_chisel::bsp::octree::Edit;
use std::time::Duration;

use bevy_chisel::net::{
    ClientPacket, ClientRequest, NetKey, NetLimits, Outcome, RejectReason, RequestRejected,
    WirePiece, WirePose, WireShape, WireTool, connect_token, start_client, start_secure_client,
};
use bevy_chisel::terrain::{CarveTool, GridTool};
use bevy_replicon::shared::message::registry::RemoteMessageRegistry;
use bevy_replicon_renet::{RenetClient, RenetServer};
use net::{
    Rng, Seen, client, client_app, random_carve, request, run_until, secure_server, server, slab,
    terrain_of,
};

const HONEST: usize = 30;
const FLOOD: usize = 3000;

fn send(app: &mut App, request: ClientRequest) {
    app.world_mut()
        .write_message(ClientPacket::Request(request));
}

fn world_tool(shape: WireShape, at: [f32; 3]) -> WireTool {
    WireTool::World(vec![WirePiece {
        shape,
        pose: WirePose {
            translation: at,
            rotation: [0.0, 0.0, 0.0, 1.0],
            scale: [1.0; 3],
        },
        sweep_to: None,
    }])
}

#[derive(Resource, Default)]
struct Refused(Vec<RequestRejected>);

#[test]
fn hostile_requests_are_refused_with_reasons_and_hurt_no_one() {
    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let limits = NetLimits::default();
    let burst = limits.burst as usize;
    let (mut server, addr) = server(slab(), limits);
    server.init_resource::<Refused>().add_systems(
        Last,
        |mut seen: ResMut<Refused>, mut r: MessageReader<RequestRejected>| {
            seen.0.extend(r.read().cloned());
        },
    );
    let mut honest = client(addr, 1, 1);
    let mut hostile = client(addr, 2, 1);
    run_until(
        &mut [&mut server, &mut honest, &mut hostile],
        20_000,
        |apps| {
            apps[1..]
                .iter_mut()
                .all(|app| terrain_of(app).is_some_and(|(_, t)| t.is_idle()))
        },
    );

    // 1. Bytes that are no request, straight onto the request channel.
    let channel = hostile
        .world()
        .resource::<RemoteMessageRegistry>()
        .client_message_channel::<ClientPacket>()
        .expect("registered") as u8;
    for garbage in [
        vec![0xFF; 7],
        vec![],
        vec![3, 200, 200, 200, 200, 200, 200, 1],
    ] {
        hostile
            .world_mut()
            .resource_mut::<RenetClient>()
            .send_message(channel, garbage);
    }
    // 2. Out of the bit budget (|v| ≤ 2^26), 3. NaN, 4. a million points,
    // 5. too large, 6. no such terrain, 7. degenerate (flat) hull.
    let far = 1i64 << 40;
    send(
        &mut hostile,
        ClientRequest::Carve {
            request: 2,
            terrain: 1,
            tool: WireTool::Grid(GridTool {
                pieces: vec![vec![[far, 0, 0], [far + 9, 0, 0], [far, 9, 0], [far, 0, 9]]],
            }),
            edit: Edit::Subtract,
        },
    );
    send(
        &mut hostile,
        ClientRequest::Carve {
            request: 3,
            terrain: 1,
            tool: world_tool(
                WireShape::Dodecahedron { radius: 0.5 },
                [f32::NAN, 2.0, 5.0],
            ),
            edit: Edit::Subtract,
        },
    );
    let million: Vec<[f32; 3]> = (0..1_000_000)
        .map(|i| {
            [
                5.0 + (i % 100) as f32 * 1e-3,
                2.0,
                5.0 + (i / 100) as f32 * 1e-5,
            ]
        })
        .collect();
    send(
        &mut hostile,
        ClientRequest::Carve {
            request: 4,
            terrain: 1,
            tool: world_tool(WireShape::Hull(million), [0.0; 3]),
            edit: Edit::Subtract,
        },
    );
    send(
        &mut hostile,
        ClientRequest::Carve {
            request: 5,
            terrain: 1,
            tool: world_tool(WireShape::Dodecahedron { radius: 500.0 }, [5.0, 2.0, 5.0]),
            edit: Edit::Subtract,
        },
    );
    send(
        &mut hostile,
        ClientRequest::Carve {
            request: 6,
            terrain: 99,
            tool: WireTool::from(&CarveTool::dodecahedron(0.3, Vec3::new(5.0, 2.0, 5.0))),
            edit: Edit::Subtract,
        },
    );
    send(
        &mut hostile,
        ClientRequest::Carve {
            request: 7,
            terrain: 1,
            tool: WireTool::Grid(GridTool {
                pieces: vec![vec![[0, 0, 0], [10, 0, 0], [0, 10, 0], [10, 10, 0]]],
            }),
            edit: Edit::Subtract,
        },
    );
    for _ in 0..4 {
        for app in [&mut server, &mut honest, &mut hostile] {
            app.update();
        }
    }
    // 8. A flood, in one frame, with the honest client carving meanwhile.
    for i in 0..FLOOD {
        let (tool, edit) = random_carve(&mut Rng(i as u64));
        request(&mut hostile, 1000 + i as u64, &tool, edit);
    }
    let mut rng = Rng(7);
    let mut sent = 0;
    let frames = run_until(
        &mut [&mut server, &mut honest, &mut hostile],
        100_000,
        |apps| {
            if sent < HONEST {
                let (tool, edit) = random_carve(&mut rng);
                request(&mut *apps[1], sent as u64, &tool, edit);
                sent += 1;
            }
            let [server, honest, hostile] = apps else {
                return false;
            };
            let done = |app: &App, n| app.world().resource::<Seen>().results.len() >= n;
            done(honest, HONEST)
                && done(hostile, FLOOD + 9)
                && [&mut **server, &mut **honest]
                    .into_iter()
                    .all(|app| terrain_of(app).is_some_and(|(_, t)| t.is_idle()))
                && terrain_of(honest).map(|(_, t)| t.journal().len())
                    == terrain_of(server).map(|(_, t)| t.journal().len())
        },
    );
    println!("settled after {frames} frames");

    let results = &hostile.world().resource::<Seen>().results;
    let reason = |id: u64| {
        results
            .iter()
            .find(|r| r.request == Some(id))
            .map(|r| r.outcome.clone())
            .unwrap_or_else(|| panic!("request {id} unanswered"))
    };
    let malformed = results
        .iter()
        .filter(|r| r.request.is_none())
        .inspect(|r| println!("malformed: {:?}", r.outcome))
        .filter(|r| matches!(r.outcome, Outcome::Rejected(RejectReason::Malformed(_))))
        .count();
    assert_eq!(malformed, 3, "each garbage packet is answered");
    for id in 2..=7 {
        println!("request {id}: {:?}", reason(id));
    }
    assert!(
        matches!(reason(2), Outcome::Rejected(RejectReason::Invalid(ref why)) if why.contains("range") || why.contains("budget"))
    );
    assert!(matches!(
        reason(3),
        Outcome::Rejected(RejectReason::Invalid(_))
    ));
    assert!(matches!(
        reason(4),
        Outcome::Rejected(RejectReason::TooManyPoints {
            points: 1_000_000,
            ..
        })
    ));
    assert!(matches!(
        reason(5),
        Outcome::Rejected(RejectReason::TooLarge { .. })
    ));
    assert!(matches!(
        reason(6),
        Outcome::Rejected(RejectReason::UnknownTerrain(99))
    ));
    assert!(matches!(
        reason(7),
        Outcome::Rejected(RejectReason::Invalid(_))
    ));
    let flood: Vec<Outcome> = (0..FLOOD as u64).map(|i| reason(1000 + i)).collect();
    let limited = flood
        .iter()
        .filter(|o| matches!(o, Outcome::Rejected(RejectReason::RateLimited)))
        .count();
    println!("flood: {limited} of {FLOOD} refused for the rate limit");
    assert!(
        limited >= FLOOD - burst - 50,
        "the flood is cut to the burst"
    );

    // The honest client was not hurt: every carve applied, same terrain.
    let honest_results = &honest.world().resource::<Seen>().results;
    assert!(
        honest_results
            .iter()
            .all(|r| matches!(r.outcome, Outcome::Applied { .. }))
    );
    let (_, h) = terrain_of(&mut honest).expect("terrain");
    let (hash, bytes) = (h.state_hash(), h.octree().to_bytes());
    let (_, s) = terrain_of(&mut server).expect("terrain");
    assert_eq!(hash, s.state_hash());
    assert!(bytes == s.octree().to_bytes());
    let refused = &server.world().resource::<Refused>().0;
    assert!(
        refused.len() >= limited + 9,
        "the server reports every refusal"
    );
}

/// A secure server admits a client whose token it signed, which then
/// carves as usual; a client with a token signed by another key, and one
/// that connects without a token, never get in.
#[test]
fn a_secure_server_admits_only_clients_with_its_tokens() {
    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let key = NetKey::generate();
    let (mut server, addr) = secure_server(slab(), &key);
    let minute = Duration::from_secs(60);

    let mut admitted = client_app(1);
    let token = connect_token(&key, 7, &[addr], minute).expect("token");
    start_secure_client(admitted.world_mut(), &token).expect("client starts");
    let mut forged = client_app(1);
    let token = connect_token(&NetKey::generate(), 8, &[addr], minute).expect("token");
    start_secure_client(forged.world_mut(), &token).expect("client starts");
    let mut plain = client_app(1);
    start_client(plain.world_mut(), addr, 9).expect("client starts");

    run_until(
        &mut [&mut server, &mut admitted, &mut forged, &mut plain],
        20_000,
        |apps| terrain_of(apps[1]).is_some_and(|(_, t)| t.is_idle()),
    );
    let (tool, edit) = random_carve(&mut Rng(7));
    request(&mut admitted, 1, &tool, edit);
    run_until(
        &mut [&mut server, &mut admitted, &mut forged, &mut plain],
        20_000,
        |apps| !apps[1].world().resource::<Seen>().results.is_empty(),
    );
    // Give the refused clients time to have been let in, were they.
    for _ in 0..200 {
        for app in [&mut server, &mut admitted, &mut forged, &mut plain] {
            app.update();
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    let results = &admitted.world().resource::<Seen>().results;
    assert!(
        matches!(results[0].outcome, Outcome::Applied { .. }),
        "the admitted client carves: {results:?}"
    );
    assert_eq!(
        server.world().resource::<RenetServer>().connected_clients(),
        1,
        "only the client with the server's token is connected"
    );
    for (name, app) in [("forged token", &mut forged), ("no token", &mut plain)] {
        assert!(terrain_of(app).is_none(), "{name}: no terrain");
        assert!(
            !app.world().resource::<RenetClient>().is_connected(),
            "{name}: not connected"
        );
    }
}
