// node_client.js: a Modbus/TCP master from the npm registry (modbus-serial)
// drives frepmill's server for test_modbus_node: commands with sequence
// numbers, float32 read-back, live-mode positions, and refused writes on a
// read-only server. Prints "key values..." lines; the C test checks them and
// what the fake service recorded. Usage: node node_client.js PORT_RW PORT_RO
"use strict";
const ModbusRTU = require("modbus-serial");

async function connect(port) {
  const c = new ModbusRTU();
  await c.connectTCP("127.0.0.1", { port });
  c.setID(1);
  c.setTimeout(2000);
  return c;
}

async function refusedCode(promise) {
  try {
    await promise;
    return "accepted";
  } catch (e) {
    return e.modbusCode !== undefined ? String(e.modbusCode) : "error:" + e.message;
  }
}

async function main() {
  const [portRw, portRo] = process.argv.slice(2).map(Number);
  const rw = await connect(portRw);

  // Pause job slot 7 under sequence number 1, then the same number twice more.
  await rw.writeRegisters(100, [2, 1, 7]);
  await rw.writeRegisters(100, [2, 1, 7]);
  await rw.writeRegisters(100, [1, 1]);
  const ack = await rw.readHoldingRegisters(28, 1);
  console.log("ack_after_repeat " + ack.data[0]);
  // Resume under number 2; then pause one register at a time (FC06).
  await rw.writeRegisters(100, [1, 2]);
  await rw.writeRegister(100, 2);
  await rw.writeRegister(102, 9);
  await rw.writeRegister(101, 3);
  const r = await rw.readHoldingRegisters(26, 3);
  console.log("regs26_28 " + r.data.join(" "));

  // Floats, high word first (the server's default): readFloatBE on the bytes.
  const f = await rw.readInputRegisters(9, 14);
  const vals = [];
  for (let i = 0; i < 7; i++) vals.push(f.buffer.readFloatBE(4 * i));
  console.log("floats " + vals.join(" "));

  // Live mode on and one position, in a single write of 110..117.
  const b = Buffer.alloc(16);
  b.writeFloatBE(10.5, 0);
  b.writeFloatBE(-20.25, 4);
  b.writeFloatBE(5.125, 8);
  b.writeUInt16BE(6, 12);
  b.writeUInt16BE(1, 14);
  const words = [];
  for (let i = 0; i < 8; i++) words.push(b.readUInt16BE(2 * i));
  await rw.writeRegisters(110, words);
  console.log("live_written 1");
  rw.close(() => {});

  const ro = await connect(portRo);
  console.log("readonly_fc16 " + (await refusedCode(ro.writeRegisters(100, [2, 4, 0]))));
  console.log("readonly_fc06 " + (await refusedCode(ro.writeRegister(101, 5))));
  console.log("readonly_live " + (await refusedCode(ro.writeRegisters(110, [0, 0]))));
  const v = await ro.readInputRegisters(0, 1);
  console.log("readonly_read " + v.data[0]);
  ro.close(() => {});
}

main().then(
  () => process.exit(0),
  (e) => {
    console.error("node_client: " + (e && e.stack ? e.stack : e));
    process.exit(1);
  }
);
