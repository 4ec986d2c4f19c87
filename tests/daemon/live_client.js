// live_client.js: drives frepmilld over Modbus with a client from the npm
// registry (modbus-serial, installed in tests/modbus/node_modules) for
// test_live.py and test_modbus.py. Steps from the command line, in order:
//   cmd:C,SEQ,ARG       one FC16 write of 100-102 (command, sequence, argument)
//   on | off            write register 117 (live mode)
//   X,Y,Z,T             one FC16 write of 110-116: a position and a tool
//   read                print "regs v0 v1 ... v28" (FC04 0-28) and
//                       "floats x y z time removed remaining rate" (9-22)
// Usage: node live_client.js PORT STEP...
"use strict";
const ModbusRTU = require("modbus-serial");

async function main() {
  const [port, ...steps] = process.argv.slice(2);
  const c = new ModbusRTU();
  await c.connectTCP("127.0.0.1", { port: Number(port) });
  c.setID(1);
  c.setTimeout(5000);
  for (const step of steps) {
    if (step.startsWith("cmd:")) {
      await c.writeRegisters(100, step.slice(4).split(",").map(Number));
      console.log("command " + step.slice(4));
    } else if (step === "on" || step === "off") {
      await c.writeRegister(117, step === "on" ? 1 : 0);
      console.log("live " + step);
    } else if (step === "read") {
      const r = await c.readInputRegisters(0, 29);
      console.log("regs " + r.data.join(" "));
      const vals = [];
      for (let i = 0; i < 7; i++) vals.push(r.buffer.readFloatBE(18 + 4 * i));
      console.log("floats " + vals.join(" "));
    } else {
      const [x, y, z, t] = step.split(",").map(Number);
      const b = Buffer.alloc(14);
      b.writeFloatBE(x, 0);
      b.writeFloatBE(y, 4);
      b.writeFloatBE(z, 8);
      b.writeUInt16BE(t, 12);
      const words = [];
      for (let i = 0; i < 7; i++) words.push(b.readUInt16BE(2 * i));
      await c.writeRegisters(110, words);
      console.log("position " + step);
    }
  }
  c.close(() => {});
}

main().catch((e) => {
  console.error("live_client: " + (e && e.message ? e.message : e));
  process.exit(1);
});
