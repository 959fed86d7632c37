//! The protocol's messages read back as written, and what a decoder refuses.

use super::*;

fn split(adjusted: Vec<u32>) -> VertexSplit {
    VertexSplit {
        v_p: 3,
        position: [1.0, 2.0, 3.0],
        normal: [0.0, 1.0, 0.0],
        v_l: Some(4),
        v_r: None,
        adjusted,
        corners: [0, 2],
        error: 0.0,
        joins_previous: false,
    }
}

fn every_kind() -> Vec<Message> {
    vec![
        Message::Hello(Hello {
            traversal: Traversal::Linear,
            fov: 1.0,
            budget: Some(60_000),
            out_of_view: true,
            back_face: false,
            scheme: Scheme::Selective,
        }),
        Message::View(ViewPacket {
            frame: 7,
            eye: [1.0, 2.0, 3.0],
            aim: [0.0, 0.0, 0.0],
            tau: 0.001,
            budget_mode: true,
            n: 500,
        }),
        Message::Bye,
        Message::Welcome(vec![WelcomeObject {
            id: 9,
            splits: 10,
            base: Mesh {
                positions: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
                normals: vec![[0.0, 0.0, 1.0]; 3],
                indices: vec![0, 1, 2],
            },
        }]),
        Message::Batch {
            frame: 7,
            objects: vec![ObjectUpdates {
                index: 0,
                collapses: vec![5, 6],
                splits: vec![NodeSplit {
                    node: 2,
                    first: 4,
                    run: vec![split(vec![1, 2]), split(vec![])],
                }],
            }],
        },
        Message::Refused("no".into()),
        Message::Resume {
            next_frame: 8,
            objects: vec![
                HeldNodes {
                    index: 0,
                    nodes: vec![3, 1, 4],
                },
                HeldNodes {
                    index: 1,
                    nodes: vec![],
                },
            ],
        },
        Message::ResumeLeaves {
            next_frame: 3,
            objects: vec![HeldLeaves {
                index: 0,
                leaves: vec![name(2, &[true, false]), name(0, &[])],
            }],
        },
        Message::SelectiveWelcome(vec![SelectiveObject {
            id: 4,
            base: SelectiveBase {
                triangles: vec![[0, 1, 2]],
                roots: vec![
                    ([0.0; 3], [0.0, 0.0, 1.0], Some(info())),
                    ([1.0, 0.0, 0.0], [0.0, 0.0, 1.0], None),
                    ([0.0, 1.0, 0.0], [0.0, 0.0, 1.0], Some(info())),
                ],
                leaves: Some(vec![[name(0, &[true]), name(1, &[]), name(2, &[false; 9])]]),
            },
        }]),
        Message::Vsplits {
            frame: 9,
            objects: vec![ObjectVsplits {
                index: 0,
                packets: vec![VsplitPacket {
                    node: name(1, &[false]),
                    cuts: [Some(name(2, &[true; 70])), None],
                    position: [1.0, 2.0, 3.0],
                    normal: [0.0, 1.0, 0.0],
                    children: [None, Some(info())],
                    run: Some(name(0, &[true, true])),
                    leaves: [
                        Some([name(1, &[false, false, true]), name(1, &[false, true])]),
                        None,
                    ],
                }],
            }],
        },
        Message::BlocksWelcome {
            levels: 2,
            objects: vec![SelectiveObject {
                id: 5,
                base: SelectiveBase {
                    triangles: vec![[0, 1, 2]],
                    roots: vec![
                        ([0.0; 3], [0.0, 0.0, 1.0], Some(info())),
                        ([1.0, 0.0, 0.0], [0.0, 0.0, 1.0], None),
                        ([0.0, 1.0, 0.0], [0.0, 0.0, 1.0], Some(info())),
                    ],
                    leaves: None,
                },
            }],
        },
        Message::Switch(Switch {
            frame: 11,
            eye: [1.0, 2.0, 3.0],
            aim: [0.0, 0.5, 0.0],
            tau: 0.002,
            objects: vec![
                ObjectSwitch {
                    index: 0,
                    down: vec![name(0, &[]), name(2, &[true, false])],
                    ahead: vec![name(1, &[false; 12])],
                    released: vec![],
                },
                ObjectSwitch {
                    index: 3,
                    down: vec![],
                    ahead: vec![],
                    released: vec![name(4, &[true; 2])],
                },
            ],
        }),
        Message::Blocks {
            frame: 11,
            predicted: true,
            objects: vec![ObjectBlocks {
                index: 0,
                blocks: vec![
                    flaneur::lod::Block {
                        top: name(0, &[]),
                        packets: vec![packet(name(0, &[])), packet(name(0, &[true]))],
                    },
                    flaneur::lod::Block {
                        top: name(2, &[true, false]),
                        packets: vec![packet(name(2, &[true, false]))],
                    },
                ],
            }],
        },
        Message::Blocks {
            frame: 12,
            predicted: false,
            objects: vec![],
        },
    ]
}

/// The first kind of the blocks scheme's messages in [`every_kind`].
const BLOCKS_KINDS: usize = 10;

/// A vsplit packet of `node` with both children's INFO.
fn packet(node: NodeName) -> VsplitPacket {
    VsplitPacket {
        node,
        cuts: [Some(name(1, &[])), Some(name(2, &[false]))],
        position: [1.0, 2.0, 3.0],
        normal: [0.0, 1.0, 0.0],
        children: [Some(info()), Some(info())],
        run: None,
        leaves: [None, None],
    }
}

/// The name of the node down `path` (true: right) from root `tree`.
fn name(tree: u32, path: &[bool]) -> NodeName {
    let node = path
        .iter()
        .fold(flaneur::lod::HeapIndex::root(), |n, &right| n.child(right));
    NodeName { tree, node }
}

fn info() -> flaneur::lod::RefineInfo {
    flaneur::lod::RefineInfo {
        centre: [1.0, 2.0, 3.0],
        axis: [0.0, 1.0, 0.0],
        radius: 0.5,
        cone_sin: 0.25,
        error: 0.01,
    }
}

#[test]
fn every_message_reads_back_as_written() {
    for m in every_kind() {
        let bytes = m.encode();
        let mut input = &bytes[..];
        let (back, len) = receive(&mut input, MAX_TO_CLIENT).unwrap().unwrap();
        assert_eq!(back, m);
        assert_eq!(len, bytes.len());
    }
}

#[test]
fn an_objects_wire_length_is_what_it_takes_in_a_batch() {
    let Message::Batch { objects, .. } = &every_kind()[4] else {
        unreachable!()
    };
    let whole = every_kind()[4].encode().len();
    // Length, kind, frame and the object count, then the one object.
    assert_eq!(whole, 4 + 1 + 4 + 4 + objects[0].wire_len());
}

#[test]
fn a_view_is_zhengs_33_bytes_after_its_frame_number() {
    let view = &every_kind()[1];
    assert_eq!(view.encode().len(), 4 + 1 + 4 + 33);
}

#[test]
fn every_cut_of_every_message_is_an_error_not_a_panic() {
    for m in every_kind() {
        let bytes = m.encode();
        for cut in 4..bytes.len() {
            let body = &bytes[4..cut];
            if let Ok(back) = Message::decode(body) {
                // Only REFUSED reads any prefix (its reason runs to the end).
                assert!(matches!(back, Message::Refused(_)), "{back:?} from {cut}");
            }
        }
    }
}

#[test]
fn counts_beyond_the_bytes_are_refused_before_anything_is_reserved() {
    let mut bytes = every_kind()[4].encode();
    // The object count, just after the kind and the frame number.
    bytes[9..13].copy_from_slice(&u32::MAX.to_le_bytes());
    let e = Message::decode(&bytes[4..]).unwrap_err();
    assert!(e.to_string().contains("a count of 4294967295"), "{e}");
}

/// A frame of many empty entries would decode to several times its bytes: the
/// counts that allow it are refused.
#[test]
fn what_a_frame_decodes_to_stays_near_its_bytes() {
    let batch = |objects: Vec<ObjectUpdates>| Message::Batch { frame: 1, objects }.encode();
    let empty = |index| ObjectUpdates {
        index,
        ..Default::default()
    };
    let refused = |bytes: Vec<u8>| Message::decode(&bytes[4..]).unwrap_err().to_string();
    let e = refused(batch(vec![empty(0)]));
    assert!(e.contains("object 0's part has no update"), "{e}");
    let many = (0..=MAX_OBJECTS as u32)
        .map(|index| ObjectUpdates {
            index,
            collapses: vec![1],
            splits: vec![],
        })
        .collect();
    let e = refused(batch(many));
    assert!(e.contains("65537 objects, above the 65536"), "{e}");
    let e = refused(batch(vec![ObjectUpdates {
        index: 0,
        collapses: vec![1; MAX_N as usize + 1],
        splits: vec![],
    }]));
    assert!(e.contains("501 collapses"), "{e}");
    let e = refused(batch(vec![ObjectUpdates {
        index: 0,
        collapses: vec![],
        splits: vec![NodeSplit {
            node: 4,
            first: 0,
            run: vec![],
        }],
    }]));
    assert!(e.contains("node 4's split has no vertex split"), "{e}");
    let resume = Message::Resume {
        next_frame: 0,
        objects: (0..=MAX_OBJECTS as u32)
            .map(|index| HeldNodes {
                index,
                nodes: vec![],
            })
            .collect(),
    };
    let e = refused(resume.encode());
    assert!(e.contains("above the 65536"), "{e}");
}

#[test]
fn bad_fields_are_named() {
    let mut hello = every_kind()[0].encode();
    hello[5] = b'X';
    let e = Message::decode(&hello[4..]).unwrap_err().to_string();
    assert!(e.contains("bad magic"), "{e}");
    let mut view = every_kind()[1].encode();
    view[9..13].copy_from_slice(&f32::NAN.to_le_bytes());
    let e = Message::decode(&view[4..]).unwrap_err().to_string();
    assert!(e.contains("not finite"), "{e}");
    let mut hello = every_kind()[0].encode();
    *hello.last_mut().unwrap() = 4;
    let e = Message::decode(&hello[4..]).unwrap_err().to_string();
    assert!(e.contains("scheme 4, not 0 to 3"), "{e}");
    let Message::SelectiveWelcome(mut objects) = every_kind()[8].clone() else {
        unreachable!()
    };
    objects[0].base.leaves = None;
    let mut welcome = Message::SelectiveWelcome(objects).encode();
    // The placement byte, then the base triangle's last corner before it.
    welcome.pop();
    // The base triangle's last corner: a root the object does not have.
    let at = welcome.len() - 4;
    welcome[at..].copy_from_slice(&7u32.to_le_bytes());
    welcome.push(0);
    let e = Message::decode(&welcome[4..]).unwrap_err().to_string();
    assert!(e.contains("corner 7, of 3 roots"), "{e}");
    let mut welcome = every_kind()[8].encode();
    // The first leaf's tree (the three leaves take 7, 7 and 8 bytes): not its root.
    let at = welcome.len() - (7 + 7 + 8);
    welcome[at..at + 4].copy_from_slice(&2u32.to_le_bytes());
    let e = Message::decode(&welcome[4..]).unwrap_err().to_string();
    assert!(e.contains("leaf in tree 2, its corner being root 0"), "{e}");
    let e = Message::decode(&[0x7f]).unwrap_err().to_string();
    assert!(e.contains("kind 0x7f"), "{e}");
    let long = (MAX_TO_SERVER as u32 + 1).to_le_bytes();
    let e = receive(&mut &long[..], MAX_TO_SERVER)
        .unwrap_err()
        .to_string();
    assert!(e.contains("above the 4096"), "{e}");
}

#[test]
fn a_switchs_frame_length_is_what_it_takes_and_is_bounded_on_its_own() {
    let Message::Switch(switch) = &every_kind()[BLOCKS_KINDS + 1] else {
        unreachable!()
    };
    assert_eq!(
        switch.frame_len() + 4,
        every_kind()[BLOCKS_KINDS + 1].encode().len()
    );
    // A SWITCH of ten thousand names: past what a server reads of other messages,
    // within its own bound.
    let long = Message::Switch(Switch {
        objects: vec![ObjectSwitch {
            index: 0,
            down: (0..10_000).map(|t| name(t, &[true; 20])).collect(),
            ..Default::default()
        }],
        ..switch.clone()
    })
    .encode();
    let e = receive(&mut &long[..], MAX_TO_SERVER)
        .unwrap_err()
        .to_string();
    assert!(e.contains("above the 4096"), "{e}");
    assert!(receive(&mut &long[..], MAX_SWITCH).unwrap().is_some());
}

/// The blocks' messages: what their decoders refuse, by name.
#[test]
fn bad_blocks_messages_are_named() {
    let refused = |bytes: Vec<u8>| Message::decode(&bytes[4..]).unwrap_err().to_string();
    let kinds = every_kind();
    // BLOCKS-WELCOME's levels: after the kind, the magic and the version.
    let mut welcome = kinds[BLOCKS_KINDS].encode();
    welcome[4 + 1 + 8 + 2] = 0;
    let e = refused(welcome);
    assert!(e.contains("blocks of 0 levels"), "{e}");
    let Message::Switch(switch) = kinds[BLOCKS_KINDS + 1].clone() else {
        unreachable!()
    };
    let e = refused(
        Message::Switch(Switch {
            objects: vec![ObjectSwitch {
                index: 2,
                ..Default::default()
            }],
            ..switch.clone()
        })
        .encode(),
    );
    assert!(e.contains("object 2's part names no block"), "{e}");
    // The view's eye: after the kind and the frame.
    let mut bad_eye = Message::Switch(switch.clone()).encode();
    bad_eye[9..13].copy_from_slice(&f32::INFINITY.to_le_bytes());
    let e = refused(bad_eye);
    assert!(e.contains("SWITCH") && e.contains("not finite"), "{e}");
    // A count of names past the bytes left.
    let mut many = Message::Switch(switch).encode();
    // The first object's down count: after the head and its index.
    let at = 4 + 1 + 4 + 12 + 12 + 4 + 4 + 4;
    many[at..at + 4].copy_from_slice(&u32::MAX.to_le_bytes());
    let e = refused(many);
    assert!(e.contains("a count of 4294967295"), "{e}");
    // BLOCKS' flags: after the kind and the frame.
    let mut flags = kinds[BLOCKS_KINDS + 2].encode();
    flags[9] = 0x03;
    let e = refused(flags);
    assert!(e.contains("unknown flags 0x03"), "{e}");
    let blocks = |blocks: Vec<flaneur::lod::Block>| {
        Message::Blocks {
            frame: 1,
            predicted: false,
            objects: vec![ObjectBlocks { index: 4, blocks }],
        }
        .encode()
    };
    let e = refused(blocks(vec![]));
    assert!(e.contains("object 4's part has no block"), "{e}");
    let e = refused(blocks(vec![flaneur::lod::Block {
        top: name(3, &[false]),
        packets: vec![],
    }]));
    assert!(e.contains("has no split"), "{e}");
}

/// A SWITCH past its bound keeps its releases and drops the tops asked ahead, from the
/// last, before those down.
#[test]
fn a_switch_is_cut_to_its_bound_by_the_tops_it_can_ask_again() {
    let Message::Switch(switch) = every_kind()[BLOCKS_KINDS + 1].clone() else {
        unreachable!()
    };
    let len = switch.frame_len();
    assert_eq!(switch.clone().within(len).unwrap(), switch);
    // The name asked ahead is 13 bits (8 bytes), the others at most 8 bits (7 bytes).
    let (ahead, name) = (8, 7);
    let cut = switch.clone().within(len - 1).unwrap();
    assert!(cut.objects[0].ahead.is_empty() && cut.objects[0].down.len() == 2);
    assert_eq!(cut.frame_len(), len - ahead);
    // Then the down tops, from the last; the releases stay.
    let cut = switch.clone().within(len - ahead - 1).unwrap();
    assert_eq!(cut.objects[0].down, switch.objects[0].down[..1]);
    assert_eq!(cut.objects[1], switch.objects[1]);
    // A part left with nothing is not sent.
    let cut = switch.clone().within(len - ahead - 2 * name).unwrap();
    assert_eq!(cut.objects, switch.objects[1..]);
    let e = switch.within(40).unwrap_err().to_string();
    assert!(e.contains("releases alone take"), "{e}");
}

/// A peer's bytes, 4 KiB a read at most, up to `cut` of them (then the connection
/// breaks); the longest buffer a read was handed.
struct Trickle {
    bytes: Vec<u8>,
    at: usize,
    cut: usize,
    longest_ask: usize,
}

impl std::io::Read for Trickle {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        self.longest_ask = self.longest_ask.max(buf.len());
        if self.at >= self.cut.min(self.bytes.len()) {
            return Err(std::io::ErrorKind::ConnectionReset.into());
        }
        let n = buf.len().min(4096).min(self.cut - self.at);
        buf[..n].copy_from_slice(&self.bytes[self.at..self.at + n]);
        self.at += n;
        Ok(n)
    }
}

/// A frame announced at the protocol's longest and cut short is read into a buffer no
/// longer than what came (and a piece), not one of the announced length; a frame that
/// comes whole in small reads is the message sent.
#[test]
fn a_frame_is_read_as_its_bytes_come_not_as_long_as_announced() {
    let resume = Message::Resume {
        next_frame: 9,
        objects: vec![HeldNodes {
            index: 0,
            nodes: (0..100_000).collect(),
        }],
    };
    let whole = resume.encode();
    let mut announced = whole.clone();
    announced[..4].copy_from_slice(&(MAX_RESUME as u32).to_le_bytes());
    let cut = 200 << 10;
    let mut peer = Trickle {
        bytes: announced,
        at: 0,
        cut,
        longest_ask: 0,
    };
    assert!(receive(&mut peer, MAX_RESUME).is_err());
    assert_eq!(peer.at, cut);
    assert!(
        peer.longest_ask <= 2 * cut,
        "a read was handed {} bytes for a frame cut at {cut}",
        peer.longest_ask
    );
    let mut peer = Trickle {
        cut: whole.len(),
        bytes: whole.clone(),
        at: 0,
        longest_ask: 0,
    };
    let (back, len) = receive(&mut peer, MAX_RESUME).unwrap().unwrap();
    assert_eq!((back, len), (resume, whole.len()));
}
