// An independent VDA 5050 2.0 master control for the twin: Siemens' vda-5050-lib MasterController.
//
// Connects to the broker, waits until every vehicle of --vehicles is ONLINE and localised, asks each
// for its factsheet, assigns each an order from where it stands along the warehouse's central aisle
// to the aisle end farther from it (two robots at the two ends swap them, head-on), waits until the
// library reports every order processed and the vehicle standing, and prints one JSON report.
// Every message a vehicle sends is validated by the library against the VDA 5050 2.0 JSON schemas
// (an invalid one is dropped by it and counted here as rejected).
// Exit 0: all orders processed without error, no state error, no rejected message; 1: a failure or
// the timeout; 2: bad arguments. Usage: node master.mjs --help.

import mqtt from "mqtt";
import lib from "vda-5050-lib";

const { MasterController, Topic, BlockingType } = lib;

const USAGE = `usage: node master.mjs --broker mqtt://HOST:PORT [--vehicles amr-1[,amr-2...]]
  [--interface uagv] [--manufacturer amr-twin] [--aisle X0,Y0;X1,Y1] [--deviation-m 0.3]
  [--timeout-s 50]`;

function parseArgs(argv) {
    const o = {
        broker: null, vehicles: ["amr-1"], interface: "uagv", manufacturer: "amr-twin",
        aisle: [[-6, 0], [4, 0]], deviation: 0.3, timeout: 50,
    };
    const fail = msg => { console.error(`error: ${msg}\n${USAGE}`); process.exit(2); };
    for (let i = 0; i < argv.length; i++) {
        const key = argv[i];
        if (key === "--help") { console.log(USAGE); process.exit(0); }
        const value = argv[++i];
        if (value === undefined) fail(`${key}: needs a value`);
        if (key === "--broker") {
            if (!/^mqtt:\/\/[^/:]+:\d+$/.test(value)) fail(`--broker ${value}: expected mqtt://HOST:PORT`);
            o.broker = value;
        } else if (key === "--vehicles") {
            o.vehicles = value.split(",");
            if (o.vehicles.some(s => !/^[A-Za-z0-9_.:-]+$/.test(s))) fail(`--vehicles ${value}: serial numbers of A-Z a-z 0-9 _ . : -, comma-separated`);
        } else if (key === "--interface") {
            if (!/^[A-Za-z0-9_.:-]+$/.test(value)) fail(`--interface ${value}: only A-Z a-z 0-9 _ . : -`);
            o.interface = value;
        } else if (key === "--manufacturer") {
            o.manufacturer = value;
        } else if (key === "--aisle") {
            const ends = value.split(";").map(p => p.split(",").map(Number));
            if (ends.length !== 2 || ends.some(p => p.length !== 2 || p.some(v => !Number.isFinite(v)))) fail(`--aisle ${value}: expected X0,Y0;X1,Y1 (m)`);
            o.aisle = ends;
        } else if (key === "--deviation-m") {
            o.deviation = Number(value);
            if (!(o.deviation > 0 && o.deviation <= 2)) fail(`--deviation-m ${value}: must be in (0, 2] m`);
        } else if (key === "--timeout-s") {
            o.timeout = Number(value);
            if (!(o.timeout > 0 && o.timeout <= 3600)) fail(`--timeout-s ${value}: must be in (0, 3600] s`);
        } else {
            fail(`unknown option ${key}`);
        }
    }
    if (!o.broker) fail("--broker is required");
    return o;
}

const opts = parseArgs(process.argv.slice(2));
const t0 = Date.now();
const since = () => (Date.now() - t0) / 1000;
const report = {
    broker: opts.broker, vehicles: {}, accepted: {}, rejected: [], failures: [], ok: false,
};
const per = Object.fromEntries(opts.vehicles.map(s => [s, {
    online: false, state: null, factsheet: null, order: null, events: [], stateErrors: [],
    processed: null, fieldViolations: 0,
}]));
report.vehicles = per;
const agvOf = serial => ({ manufacturer: opts.manufacturer, serialNumber: serial });
const delivered = new Set();  // topic/serial/headerId of every message the library passed on
let raw = null;

// The library drops an inbound message that fails its 2.0 schema validation with this line.
const consoleError = console.error;
console.error = (...args) => {
    if (typeof args[0] === "string" && args[0].startsWith("Drop inbound message")) {
        report.rejected.push({ topic: args[1], error: String(args[2]), t_s: since() });
    }
    consoleError(...args);
};

const master = new MasterController(
    { interfaceName: opts.interface, transport: { brokerUrl: opts.broker }, vdaVersion: "2.0.0" },
    { targetAgvs: { manufacturer: opts.manufacturer } },
);

function accept(topic, obj, subject) {
    report.accepted[topic] = (report.accepted[topic] ?? 0) + 1;
    delivered.add(`${topic}/${subject.serialNumber}/${obj.headerId}`);
    const v = per[subject.serialNumber];
    if (v === undefined) return;
    if (topic === Topic.State) {
        v.state = obj;
        if (obj.safetyState.fieldViolation) v.fieldViolations += 1;
        for (const e of obj.errors) {
            if (!v.stateErrors.some(x => x.errorType === e.errorType && x.errorDescription === e.errorDescription)) {
                v.stateErrors.push(e);
            }
        }
    } else if (topic === Topic.Factsheet) {
        v.factsheet = obj;
    }
}

function until(what, predicate) {
    return new Promise((resolve, reject) => {
        const poll = () => {
            if (predicate()) return resolve();
            if (report.rejected.length) return reject(new Error(`a message rejected while waiting for ${what}`));
            if (since() > opts.timeout) return reject(new Error(`timeout after ${opts.timeout} s waiting for ${what}`));
            setTimeout(poll, 20);
        };
        poll();
    });
}

function route(serial) {
    // From where the vehicle stands to the aisle end farther from it; with one vehicle through a
    // node in the aisle's middle (with several they would all aim at that one point).
    const pos = per[serial].state.agvPosition;
    const [a, b] = opts.aisle;
    const far = Math.hypot(pos.x - a[0], pos.y - a[1]) > Math.hypot(pos.x - b[0], pos.y - b[1]) ? a : b;
    const mid = [(a[0] + b[0]) / 2, (a[1] + b[1]) / 2];
    const heading = Math.atan2(far[1] - pos.y, far[0] - pos.x);
    const at = (x, y, dev, theta) => ({
        x, y, mapId: pos.mapId, allowedDeviationXy: dev, ...(theta === undefined ? {} : { theta, allowedDeviationTheta: 0.5 }),
    });
    const places = [["start", at(pos.x, pos.y, 0.5)], ["middle", at(mid[0], mid[1], opts.deviation)],
        ["end", at(far[0], far[1], opts.deviation, heading)]].filter(([name]) => name !== "middle" || opts.vehicles.length === 1);
    const ids = places.map(([name]) => `${serial}-${name}`);
    const nodes = places.map(([, nodePosition], i) => ({ nodeId: ids[i], sequenceId: 2 * i, released: true, nodePosition, actions: [] }));
    const edges = ids.slice(1).map((_id, i) => ({
        edgeId: `${ids[i]}-${ids[i + 1]}`, sequenceId: 2 * i + 1, released: true,
        startNodeId: ids[i], endNodeId: ids[i + 1], actions: [],
    }));
    return { orderId: `${serial}-${master.createUuid()}`, orderUpdateId: 0, nodes, edges };
}

function event(serial, kind, detail) {
    per[serial].events.push({ t_s: since(), event: kind, ...detail });
}

async function main() {
    master.trackAgvs((agvId, connectionState) => {
        const v = per[agvId.serialNumber];
        if (v) {
            v.online = connectionState === "ONLINE";
            event(agvId.serialNumber, "connection", { connectionState });
        }
    });
    await master.start();
    for (const topic of [Topic.State, Topic.Visualization, Topic.Connection, Topic.Factsheet]) {
        await master.subscribe(topic, { manufacturer: opts.manufacturer }, (obj, subject) => accept(topic, obj, subject));
    }
    // A plain MQTT client beside the library: every vehicle message it sees must reach the library.
    raw = { seen: [], client: mqtt.connect(opts.broker, { clientId: `raw-${master.createUuid()}` }) };
    raw.client.on("message", (topic, payload) => {
        const [, , , serial, sub] = topic.split("/");
        if (["state", "visualization", "connection", "factsheet"].includes(sub)) {
            try { raw.seen.push(`${sub}/${serial}/${JSON.parse(payload.toString()).headerId}`); }
            catch { raw.seen.push(`${sub}/${serial}/not-json`); }
        }
    });
    await new Promise((resolve, reject) => {
        raw.client.on("connect", () => raw.client.subscribe(`${opts.interface}/v2/${opts.manufacturer}/+/+`, { qos: 1 }, err => err ? reject(err) : resolve()));
        raw.client.on("error", reject);
    });

    await until("the vehicles ONLINE and localised", () => opts.vehicles.every(s => per[s].online && per[s].state?.agvPosition?.positionInitialized));
    for (const serial of opts.vehicles) {
        const actionId = `factsheet-${serial}`;
        await master.initiateInstantActions(agvOf(serial), {
            // vda-5050-lib 1.4 keeps 1.1's field name instantActions in 2.0 (the 2.0 schema: actions).
            instantActions: [{ actionId, actionType: "factsheetRequest", blockingType: BlockingType.None, actionParameters: [] }],
        }, {
            onActionStateChanged: (as, err) => event(serial, "instantAction", { actionId, actionStatus: as.actionStatus, error: err ?? null }),
            onActionError: err => event(serial, "instantActionError", { actionId, error: err }),
        });
    }
    await until("the factsheets and factsheetRequest FINISHED", () => opts.vehicles.every(s => per[s].factsheet
        && per[s].events.some(e => e.event === "instantAction" && e.actionStatus === "FINISHED")));

    for (const serial of opts.vehicles) {
        const order = route(serial);
        per[serial].order = order;
        await master.assignOrder(agvOf(serial), order, {
            onOrderProcessed: (withError, byCancelation, active) => {
                per[serial].processed = { withError: withError ?? null, byCancelation, active, t_s: since() };
                event(serial, "orderProcessed", per[serial].processed);
            },
            onNodeTraversed: node => event(serial, "nodeTraversed", { nodeId: node.nodeId }),
            onEdgeTraversing: (edge, _s, _e, changes, n) => n <= 1 && event(serial, "edgeTraversing", { edgeId: edge.edgeId, changes }),
            onEdgeTraversed: edge => event(serial, "edgeTraversed", { edgeId: edge.edgeId }),
        });
        event(serial, "orderAssigned", { orderId: order.orderId });
    }
    await until("every order processed, or an error in a state", () => opts.vehicles.every(s => per[s].processed) || opts.vehicles.some(s => per[s].stateErrors.length));
    await until("the vehicles standing", () => opts.vehicles.every(s => per[s].stateErrors.length || !per[s].state.driving));
}

function finish(code) {
    for (const serial of opts.vehicles) {
        const v = per[serial];
        if (!v.processed) report.failures.push(`${serial}: order not processed`);
        else if (v.processed.withError) report.failures.push(`${serial}: order processed with error ${JSON.stringify(v.processed.withError)}`);
        else if (v.processed.byCancelation) report.failures.push(`${serial}: order processed by cancelation`);
        if (v.stateErrors.length) report.failures.push(`${serial}: errors in its state: ${JSON.stringify(v.stateErrors)}`);
        if (v.state?.driving) report.failures.push(`${serial}: still driving`);
        const last = v.order?.nodes.at(-1);
        v.lastNode = last ? { nodeId: last.nodeId, ...last.nodePosition } : null;
        const at = v.state?.agvPosition;
        if (last && at && Math.hypot(at.x - last.nodePosition.x, at.y - last.nodePosition.y) > last.nodePosition.allowedDeviationXy) {
            report.failures.push(`${serial}: stands at (${at.x}, ${at.y}), beyond the last node's allowedDeviationXy`);
        }
        v.finalState = v.state;
        delete v.state;
    }
    if (raw) {
        const lost = raw.seen.filter(k => !delivered.has(k));
        if (lost.length) report.rejected.push({ notDeliveredByLibrary: lost.slice(0, 20), count: lost.length });
    }
    for (const topic of ["state", "visualization", "connection", "factsheet"]) {
        if (!report.accepted[topic]) report.failures.push(`no ${topic} message accepted`);
    }
    if (report.rejected.length) report.failures.push(`${report.rejected.length} message(s) rejected by the 2.0 schemas`);
    report.ok = code === 0 && report.failures.length === 0;
    report.wall_s = since();
    process.stdout.write(JSON.stringify(report) + "\n");
    process.exit(report.ok ? 0 : 1);
}

const watchdog = setTimeout(() => { report.failures.push(`timeout after ${opts.timeout + 5} s`); finish(1); }, (opts.timeout + 5) * 1000);
main()
    .then(async () => {
        raw.client.end(true);
        await new Promise(r => setTimeout(r, 300));  // what the library still has in flight
        await master.stop();
        clearTimeout(watchdog);
        finish(0);
    })
    .catch(err => {
        report.failures.push(String(err.message ?? err));
        finish(1);
    });
