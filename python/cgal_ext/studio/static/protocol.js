// The WebSocket to the studio's server (doc/studio.md, "Protocol"): JSON commands out, JSON replies and binary
// frames of arrays in. A binary frame is a little-endian uint32 header length, the JSON header naming its arrays,
// padding to 4 bytes, then the arrays.
import { clearError, showError, status, studio } from './shared.js';

const TYPES = { '<f4': Float32Array, '<u4': Uint32Array, '<u2': Uint16Array, '|i1': Int8Array, '|u1': Uint8Array,
                '<i4': Int32Array };

export function unpack(buffer) {
  const length = new DataView(buffer).getUint32(0, true);
  const header = JSON.parse(new TextDecoder().decode(new Uint8Array(buffer, 4, length)));
  const arrays = {};
  for (const a of header.arrays) {
    const Type = TYPES[a.dtype];
    if (!Type) throw new Error(`array ${a.name} of an unknown type ${a.dtype}`);
    const count = a.shape.reduce((x, y) => x * y, 1);
    arrays[a.name] = new Type(buffer, 4 + length + a.offset, count);
  }
  return [header, arrays];
}

export class Connection {
  // onCommand(message) for JSON, onArrays(header, arrays) for binary frames.
  constructor(token, { onCommand, onArrays }) {
    this.token = token;
    this.onCommand = onCommand;
    this.onArrays = onArrays;
    this.ws = null;
    this.refused = false;
  }

  connect() {
    const ws = new WebSocket(`ws://${location.host}/ws?token=${encodeURIComponent(this.token)}`);
    ws.binaryType = 'arraybuffer';
    this.ws = ws;
    ws.onopen = () => status('connected');
    ws.onclose = (event) => {
      if (this.refused) return;
      showError(`connection to the studio closed (${event.code}${event.reason ? ': ' + event.reason : ''}); reconnecting`);
      setTimeout(() => this.connect(), 1000);
    };
    ws.onmessage = (event) => {
      try {
        if (typeof event.data === 'string') {
          const m = JSON.parse(event.data);
          if (m.type === 'refused') this.refused = true;
          this.onCommand(m);
        } else {
          const [header, arrays] = unpack(event.data);
          studio.timings.push([header.type, performance.now()]);
          this.onArrays(header, arrays);
        }
      } catch (error) { // a bug of the page's: shown, not swallowed
        showError(`the page failed on a message from the server: ${error}`);
        console.error(error);
      }
    };
  }

  get open() { return this.ws && this.ws.readyState === 1; }

  send(command) {
    if (!this.open) { showError('not connected to the studio server'); return false; }
    clearError();
    this.ws.send(JSON.stringify(command));
    return true;
  }

  // A selection: the header's JSON with the count, then the indices as uint32.
  sendIndices(header, indices) {
    if (!this.open) { showError('not connected to the studio server'); return false; }
    const text = new TextEncoder().encode(JSON.stringify(Object.assign({ count: indices.length }, header)));
    const length = Math.ceil(text.length / 4) * 4;
    const buffer = new ArrayBuffer(4 + length + 4 * indices.length);
    new DataView(buffer).setUint32(0, length, true);
    new Uint8Array(buffer, 4, length).fill(32).set(text);
    new Uint32Array(buffer, 4 + length).set(indices);
    clearError();
    this.ws.send(buffer);
    return true;
  }
}
