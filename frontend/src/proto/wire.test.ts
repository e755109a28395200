// The generated TypeScript (protobuf-es) against the same hand-built byte vectors as the
// Python test tests/proto/test_wire.py, so the browser and the backend agree with the
// league's field numbers.
import { create, fromBinary, toBinary } from "@bufbuild/protobuf";
import { describe, expect, it } from "vitest";
import { RobotControlSchema } from "../gen/sslpb/ssl_simulation_robot_control_pb";
import { SSL_WrapperPacketSchema } from "../gen/sslpb/ssl_vision_wrapper_pb";
import { RobotCommandSetSchema, Team } from "../gen/sslpb/touchline_pb";

const hex = (s: string) => Uint8Array.from(s.match(/../g)!.map((b) => parseInt(b, 16)));
const toHex = (b: Uint8Array) => Array.from(b, (x) => x.toString(16).padStart(2, "0")).join("");

const WRAPPER = hex(
  "0a53080711000000000000f83f19000000000000fc3f20022a190d0000003f1d0000c84225000048c3350000803f" +
    "3d000000403a200d0000803f10031d00002041250000a0412d0000803e35000000003d00000000",
);
const ROBOT_CONTROL = hex("0a1a08031211120f0d0000803f15000000bf1d000000401d00008040");

describe("protobuf wire compatibility", () => {
  it("decodes a hand-built SSL_WrapperPacket", () => {
    const p = fromBinary(SSL_WrapperPacketSchema, WRAPPER);
    const d = p.detection!;
    expect([d.frameNumber, d.tCapture, d.tSent, d.cameraId]).toEqual([7, 1.5, 1.75, 2]);
    expect([d.balls[0]!.x, d.balls[0]!.y]).toEqual([100, -200]);
    const r = d.robotsBlue[0]!;
    expect([r.robotId, r.x, r.y, r.orientation]).toEqual([3, 10, 20, 0.25]);
    expect(toHex(toBinary(SSL_WrapperPacketSchema, p))).toBe(toHex(WRAPPER));
  });

  it("encodes RobotControl to the hand-built bytes", () => {
    const m = create(RobotControlSchema, {
      robotCommands: [
        {
          id: 3,
          kickSpeed: 4,
          moveCommand: {
            command: { case: "localVelocity", value: { forward: 1, left: -0.5, angular: 2 } },
          },
        },
      ],
    });
    expect(toHex(toBinary(RobotControlSchema, m))).toBe(toHex(ROBOT_CONTROL));
  });

  it("round-trips Touchline's command set with the team enum numbers of the GC", () => {
    const m = create(RobotCommandSetSchema, {
      createdTimeNs: 10n,
      sequence: 1n,
      stopAll: true,
      commands: [{ team: Team.BLUE, id: 4, forwardMps: 1, angularRadps: -2 }],
    });
    // same bytes as tests/proto/test_wire.py::test_touchline_command_set_layout
    expect(toHex(toBinary(RobotCommandSetSchema, m))).toBe(
      "080a1801220e080210041d0000803f2d000000c02801",
    );
    expect(Team.BLUE).toBe(2);
  });
});
