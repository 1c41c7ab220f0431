//! Resume from a feed hold, through the in-process simulator under a paused tokio clock, in
//! each firmware's flavour: a `~` sent while the hold decelerates (`Hold:1`) is dropped, as
//! GRBL 1.1h, grblHAL and FluidNC drop it, and [`GrblClient::cycle_start_confirmed`] waits for
//! `Hold:0`, sends `~` then, and confirms the controller left the hold.

mod common;

use std::time::Duration;

use cell_grbl::cycle_start::{CycleStart, CycleStartError};
use cell_grbl::protocol::{MachineState, Realtime};
use cell_grbl::sim::{SimConfig, SimEvent, SimFirmware, SimHandle};
use cell_grbl::stream::FlowControl;
use common::*;

const FLAVOURS: [SimFirmware; 3] = [
    SimFirmware::Grbl11h,
    SimFirmware::GrblHal,
    SimFirmware::FluidNc,
];

/// The test program's cuts run at 1200 mm/min (20 mm/s); at 20 mm/s² a feed hold takes a
/// second to stop, as a heavy gantry's does.
fn slow_to_stop(firmware: SimFirmware, accel_mm_s2: f64) -> SimConfig {
    SimConfig {
        accel_mm_s2,
        ..SimConfig::for_firmware(firmware)
    }
}

/// The states the simulator was in when each `~` arrived.
fn cycle_starts(sim: &SimHandle) -> Vec<MachineState> {
    sim.events()
        .iter()
        .filter_map(|e| match e {
            SimEvent::Realtime {
                command: Realtime::CycleStart,
                state,
                ..
            } => Some(*state),
            _ => None,
        })
        .collect()
}

/// Streams `p` in the background and waits until the machine is cutting.
async fn cutting(
    sim: &SimHandle,
    client: &cell_grbl::stream::GrblClient,
    p: &cell_grbl::program::Program,
) -> tokio::task::JoinHandle<Result<cell_grbl::stream::JobReport, cell_grbl::stream::StreamError>> {
    let streamer = {
        let (client, p) = (client.clone(), p.clone());
        tokio::spawn(async move { client.stream(&p).await })
    };
    sim.wait_for(WAIT, |s| s.state == MachineState::Run && s.executed > 40)
        .await
        .expect("the machine cuts");
    streamer
}

#[tokio::test(start_paused = true)]
async fn a_resume_right_after_a_hold_waits_for_the_stop_and_the_program_runs_to_the_end() {
    for firmware in FLAVOURS {
        let p = program(300);
        let (sim, client) =
            in_process(slow_to_stop(firmware, 20.0), FlowControl::CharacterCounting).await;
        let streamer = cutting(&sim, &client, &p).await;
        client.hold().await.unwrap();
        let resumed = client
            .cycle_start_confirmed(Duration::from_secs(3))
            .await
            .unwrap_or_else(|e| panic!("{firmware:?}: {e}"));
        match &resumed {
            CycleStart::Resumed {
                from,
                to,
                waited_for_hold,
            } => {
                assert_eq!(*from, MachineState::Hold(0), "{firmware:?}");
                assert_eq!(*to, MachineState::Run, "{firmware:?}");
                assert!(
                    *waited_for_hold >= Duration::from_millis(500),
                    "{firmware:?}: the deceleration was waited out ({waited_for_hold:?})"
                );
            }
            other => panic!("{firmware:?}: {other:?}"),
        }
        assert!(resumed.to_string().contains("taken"), "{resumed}");
        assert_eq!(
            cycle_starts(&sim),
            [MachineState::Hold(0)],
            "{firmware:?}: one `~`, sent once the hold was complete"
        );
        streamer
            .await
            .unwrap()
            .unwrap_or_else(|e| panic!("{firmware:?}: {e}"));
        assert_eq!(
            sim.executed_lines(),
            texts(&p),
            "{firmware:?}: every line ran"
        );
    }
}

#[tokio::test(start_paused = true)]
async fn a_bare_cycle_start_during_the_deceleration_is_dropped_and_the_machine_stays_held() {
    // What the bridge did before: `~` at once. The simulator drops it, as the firmwares do.
    for firmware in FLAVOURS {
        let p = program(300);
        let (sim, client) =
            in_process(slow_to_stop(firmware, 20.0), FlowControl::CharacterCounting).await;
        let _streamer = cutting(&sim, &client, &p).await;
        client.hold().await.unwrap();
        client.resume().await.unwrap();
        tokio::time::sleep(Duration::from_secs(5)).await;
        assert_eq!(cycle_starts(&sim), [MachineState::Hold(1)], "{firmware:?}");
        assert_eq!(
            sim.snapshot().state,
            MachineState::Hold(0),
            "{firmware:?}: still held"
        );
    }
}

#[tokio::test(start_paused = true)]
async fn a_hold_that_does_not_stop_in_time_gets_no_cycle_start_and_says_so() {
    // 20 mm/s at 1 mm/s²: twenty seconds to stop, against a 2 s resume.
    let p = program(300);
    let (sim, client) = in_process(
        slow_to_stop(SimFirmware::Grbl11h, 1.0),
        FlowControl::CharacterCounting,
    )
    .await;
    let streamer = cutting(&sim, &client, &p).await;
    client.hold().await.unwrap();
    let err = client
        .cycle_start_confirmed(Duration::from_secs(2))
        .await
        .expect_err("the hold is still decelerating");
    match &err {
        CycleStartError::HoldNotComplete { state, waited } => {
            assert_eq!(*state, MachineState::Hold(1));
            assert!(*waited >= Duration::from_secs(2), "{waited:?}");
        }
        other => panic!("{other:?}"),
    }
    let message = err.to_string();
    assert!(
        message.contains("Hold:1") && message.contains("not sent") && message.contains("held"),
        "{message}"
    );
    assert!(cycle_starts(&sim).is_empty(), "no `~` went out");
    // Once it has stopped, a resume is taken and the program ends.
    sim.wait_for(WAIT, |s| s.state == MachineState::Hold(0))
        .await
        .expect("the hold completes");
    let resumed = client
        .cycle_start_confirmed(Duration::from_secs(2))
        .await
        .unwrap();
    assert!(matches!(resumed, CycleStart::Resumed { .. }), "{resumed:?}");
    streamer.await.unwrap().unwrap();
    assert_eq!(sim.executed_lines(), texts(&p));
}

#[tokio::test(start_paused = true)]
async fn a_resume_with_nothing_held_sends_nothing() {
    let p = program(300);
    let (sim, client) = in_process(
        slow_to_stop(SimFirmware::Grbl11h, 20.0),
        FlowControl::CharacterCounting,
    )
    .await;
    // Idle: nothing to resume, an error that says so.
    let err = client
        .cycle_start_confirmed(Duration::from_secs(2))
        .await
        .expect_err("idle");
    assert!(
        matches!(err, CycleStartError::NothingToResume(MachineState::Idle)),
        "{err:?}"
    );
    assert!(err.to_string().contains("not sent"), "{err}");
    // Running: not held, nothing sent, the program goes on.
    let streamer = cutting(&sim, &client, &p).await;
    let running = client
        .cycle_start_confirmed(Duration::from_secs(2))
        .await
        .unwrap();
    assert_eq!(running, CycleStart::NotHeld(MachineState::Run));
    assert!(cycle_starts(&sim).is_empty());
    streamer.await.unwrap().unwrap();
    assert_eq!(sim.executed_lines(), texts(&p));
}
