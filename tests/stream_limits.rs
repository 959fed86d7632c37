//! `flaneur serve-stream`'s limits as a client meets them: a real server process on
//! loopback, real TCP clients, the server's memory read from `/proc/PID/status`. At most
//! `--max-sessions` at once, the next told why; no message past `--session-mb`, refused
//! before it is read; and rounds of hundreds of sessions, good and bad, that leave its
//! memory where it was.

mod common;

use std::io::{BufRead, BufReader, Write};
use std::net::TcpStream;
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::thread;
use std::time::Duration;

use flaneur::lod::Traversal;
use flaneur::Database;
use flaneur_stream::protocol::{receive, Message, MAX_RESUME, MAX_TO_CLIENT};
use flaneur_stream::{Hello, Scheme, StreamClient, StreamError, ViewPacket};

const WAIT: Duration = Duration::from_secs(20);
const MIB: u64 = 1 << 20;

/// A `flaneur serve-stream` process, killed when dropped; its printed lines come out
/// of `lines` as it prints them (read on a thread, so that it never waits on its
/// output).
struct Server {
    child: Child,
    addr: String,
    lines: mpsc::Receiver<String>,
}

impl Server {
    fn start(db: &std::path::Path, extra: &[&str]) -> Server {
        let mut child = Command::new(env!("CARGO_BIN_EXE_flaneur"))
            .args(["serve-stream", db.to_str().unwrap(), "--port", "0"])
            .args(extra)
            .stdout(Stdio::piped())
            .spawn()
            .unwrap();
        let out = BufReader::new(child.stdout.take().unwrap());
        let (tx, lines) = mpsc::channel();
        thread::spawn(move || {
            for line in out.lines().map_while(Result::ok) {
                if tx.send(line).is_err() {
                    return;
                }
            }
        });
        let first = lines.recv_timeout(WAIT).expect("the server's first line");
        let addr = first
            .split("tcp://")
            .nth(1)
            .and_then(|rest| rest.split(';').next())
            .unwrap_or_else(|| panic!("no address in {first}"))
            .to_string();
        Server { child, addr, lines }
    }

    /// The server's resident memory, bytes.
    fn rss(&self) -> u64 {
        let status = std::fs::read_to_string(format!("/proc/{}/status", self.child.id())).unwrap();
        let kb = status
            .lines()
            .find_map(|l| l.strip_prefix("VmRSS:"))
            .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
            .expect("VmRSS in /proc/PID/status");
        kb << 10
    }

    /// The next `n` sessions' ends the server printed.
    fn ends(&self, n: usize) -> Vec<String> {
        (0..n)
            .map(|i| {
                self.lines
                    .recv_timeout(WAIT)
                    .unwrap_or_else(|_| panic!("session end {i} of {n} not printed"))
            })
            .collect()
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// A small city whose buildings above 1,000 triangles are landmarks.
fn city() -> common::City {
    common::city(30, 3, &common::with_landmarks())
}

fn hello(scheme: Scheme) -> Hello {
    Hello {
        traversal: Traversal::Priority,
        fov: 1.0,
        budget: None,
        out_of_view: true,
        back_face: true,
        scheme,
    }
}

/// A view from above the middle of `db`, as frame `frame`.
fn view(db: &std::path::Path, frame: u32) -> ViewPacket {
    let b = Database::open(db).unwrap().bounds();
    ViewPacket {
        frame,
        eye: (b.center() + glam::Vec3::new(0.0, 200.0, 0.0)).to_array(),
        aim: b.center().to_array(),
        tau: 0.0001,
        budget_mode: false,
        n: 500,
    }
}

/// A connection that has said HELLO and read the server's greeting.
fn greeted(addr: &str, scheme: Scheme) -> TcpStream {
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(WAIT)).unwrap();
    s.write_all(&Message::Hello(hello(scheme)).encode())
        .unwrap();
    match receive(&mut s, MAX_TO_CLIENT).unwrap() {
        Some((Message::Refused(why), _)) => panic!("refused: {why}"),
        Some(_) => s,
        None => panic!("closed before its greeting"),
    }
}

/// Reads what the server sends on `s` until it closes: its REFUSED reason, if one came.
fn refusal(s: &mut TcpStream) -> Option<String> {
    let mut reason = None;
    while let Ok(Some((m, _))) = receive(s, MAX_TO_CLIENT) {
        if let Message::Refused(why) = m {
            reason = Some(why);
        }
    }
    reason
}

#[test]
fn the_session_past_the_limit_is_told_why_and_a_freed_place_is_taken() {
    let c = city();
    let server = Server::start(&c.db, &["--max-sessions", "3"]);
    let dag = hello(Scheme::Dag);
    let mut held: Vec<StreamClient> = (0..3)
        .map(|_| StreamClient::connect(&server.addr, dag, WAIT).unwrap())
        .collect();
    // The fourth is answered REFUSED, saying why, and the server's log says so too.
    match StreamClient::connect(&server.addr, dag, WAIT) {
        Err(StreamError::Refused(why)) => {
            assert!(why.contains("most sessions at once (3)"), "{why}")
        }
        other => panic!("the fourth session: {other:?}"),
    }
    let [logged] = &server.ends(1)[..] else {
        unreachable!()
    };
    assert!(logged.contains("most sessions at once (3)"), "{logged}");
    // A client that sends nothing at all hears it too.
    let mut silent = TcpStream::connect(&server.addr).unwrap();
    silent.set_read_timeout(Some(WAIT)).unwrap();
    let said = refusal(&mut silent).expect("a reason before the close");
    assert!(said.contains("most sessions at once (3)"), "{said}");
    server.ends(1);
    // The three held go on; one ends, and its place is taken.
    let v = view(&c.db, 1);
    for client in &mut held {
        client.send_view(&v).unwrap();
        client.receive_batch().unwrap();
    }
    held.pop().unwrap().bye().unwrap();
    let [ended] = &server.ends(1)[..] else {
        unreachable!()
    };
    assert!(ended.ends_with("the client ended it"), "{ended}");
    let mut next = StreamClient::connect(&server.addr, dag, WAIT).unwrap();
    next.send_view(&v).unwrap();
    assert!(next.receive_batch().unwrap().splits > 0);
}

/// Connections that each announce a RESUME of 16 MiB (what the protocol allows) and
/// send all of it but its last byte: above the default budget of 4 MiB a session, each
/// is refused once its length is read, and the server's memory does not grow by them
/// (it grew by about 16 MiB each when the frame was read whole into a buffer of the
/// announced length).
#[test]
fn a_message_past_the_session_budget_is_refused_before_it_is_read() {
    let c = city();
    let server = Server::start(&c.db, &[]);
    // One whole session first, so that what any session makes once is made.
    let mut warm = StreamClient::connect(&server.addr, hello(Scheme::Dag), WAIT).unwrap();
    warm.send_view(&view(&c.db, 1)).unwrap();
    warm.receive_batch().unwrap();
    warm.bye().unwrap();
    server.ends(1);
    let before = server.rss();
    const CLIENTS: usize = 6;
    let announced = MAX_RESUME as u32;
    let clients: Vec<TcpStream> = thread::scope(|scope| {
        let senders: Vec<_> = (0..CLIENTS)
            .map(|_| {
                scope.spawn(|| {
                    let mut s = greeted(&server.addr, Scheme::Dag);
                    let mut frame = announced.to_le_bytes().to_vec();
                    frame.push(0x04);
                    let piece = vec![0u8; 1 << 20];
                    let _ = s.write_all(&frame);
                    // Stops at the first write the server's close fails.
                    let mut left = announced as usize - 2;
                    while left > 0 {
                        let n = left.min(piece.len());
                        if s.write_all(&piece[..n]).is_err() {
                            break;
                        }
                        left -= n;
                    }
                    s
                })
            })
            .collect();
        senders.into_iter().map(|t| t.join().unwrap()).collect()
    });
    // What the server read of them, it holds now (the connections stay open).
    thread::sleep(Duration::from_millis(300));
    let after = server.rss();
    assert!(
        after <= before + 16 * MIB,
        "{CLIENTS} messages of {announced} bytes sent: the server's memory went from {} to {} MiB",
        before / MIB,
        after / MIB
    );
    for mut s in clients {
        let why = refusal(&mut s).expect("a reason before the close");
        assert!(
            why.contains(&format!("a frame of {announced} bytes")) && why.contains("memory budget"),
            "{why}"
        );
    }
    for logged in server.ends(CLIENTS) {
        assert!(logged.contains("memory budget"), "{logged}");
    }
}

/// One round's sessions, by four client threads: of every four, a session of Zheng's
/// scheme with two views, a truly selective one and one of blocks that only say HELLO
/// and BYE, and one that sends half of a 2 MiB RESUME and goes away.
fn round(addr: &str, views: [ViewPacket; 2], sessions: usize) {
    thread::scope(|scope| {
        for t in 0..4 {
            scope.spawn(move || {
                for i in (t..sessions).step_by(4) {
                    match i % 4 {
                        0 => {
                            let mut client =
                                StreamClient::connect(addr, hello(Scheme::Dag), WAIT).unwrap();
                            for v in &views {
                                client.send_view(v).unwrap();
                                client.receive_batch().unwrap();
                            }
                            client.bye().unwrap();
                        }
                        1 | 2 => {
                            let scheme = [Scheme::Selective, Scheme::Blocks][i % 4 - 1];
                            let mut s = greeted(addr, scheme);
                            s.write_all(&Message::Bye.encode()).unwrap();
                        }
                        _ => {
                            let mut s = greeted(addr, Scheme::Dag);
                            let mut frame = (2u32 << 20).to_le_bytes().to_vec();
                            frame.push(0x04);
                            frame.resize(1 << 20, 0);
                            let _ = s.write_all(&frame);
                        }
                    }
                }
            });
        }
    });
}

/// The soak: 20 rounds of 200 sessions each. What the server makes once (the truly
/// selective sources, its threads' first memory) is made in the first rounds; after
/// the second, its memory must stay within 16 MiB of where it was.
#[test]
fn twenty_rounds_of_two_hundred_sessions_leave_the_servers_memory_where_it_was() {
    let c = city();
    let server = Server::start(&c.db, &[]);
    let views = [view(&c.db, 1), view(&c.db, 2)];
    let mut rss = Vec::new();
    for _ in 0..20 {
        round(&server.addr, views, 200);
        server.ends(200);
        rss.push(server.rss());
    }
    let mib: Vec<String> = rss
        .iter()
        .map(|r| format!("{:.1}", *r as f64 / MIB as f64))
        .collect();
    eprintln!(
        "the server's memory after each round, MiB: {}",
        mib.join(" ")
    );
    assert!(
        rss[19] <= rss[1] + 16 * MIB,
        "the server's memory crept over the rounds, MiB: {}",
        mib.join(" ")
    );
}
