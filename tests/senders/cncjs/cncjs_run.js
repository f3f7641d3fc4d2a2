#!/usr/bin/env node
// Streams a G-code program to a controller through CNCjs (npm `cncjs`, the
// pinned version in package.json), a real grbl sender: its own server, its
// own Grbl controller code (character counting against a 120-byte budget,
// `?` every 250 ms, `$G` every 500 ms, `$$` on connect), driven headless over
// socket.io as its web page or a pendant drives it. Prints one JSON object on
// stdout with what CNCjs saw.
//
// usage: node cncjs_run.js PORT PROGRAM [options]
//
//   --timeout S             give up after S seconds (default 300)
//   --feedhold WHEN         press Feed Hold (`feedhold`) at WHEN, then Cycle
//                           Start (`cyclestart`) once CNCjs shows the
//                           controller held (Hold:0) and --hold-for has passed
//   --hold-for S            seconds to stay held before Cycle Start (0.5)
//   --override WHEN:CLICKS  feed override clicks at WHEN: a comma list of
//                           +10, -10, +1, -1 and 0 (100 %), e.g. 5:+10,+10
//                           (repeatable)
//   --jog LINE              a jog sent as CNCjs' `gcode` command before the
//                           program, e.g. '$J=G91 G21 Z-1 F300' (repeatable);
//                           it waits for the `ok` and the controller's Idle
//   --console LINE          a line typed in CNCjs' console before the program
//                           (its `gcode` command too, e.g. '$450=1'), in
//                           order with the jogs; waited for as a jog
//   --resume-after S        when the program pauses the job (M0, M1) and CNCjs
//                           shows the controller held, press Resume
//                           (`gcode:resume`) after S seconds (default 0.5;
//                           `never` leaves it paused)
//   --operator S            a program stop the controller asks the operator
//                           for (`[MSG:… then cycle start]`, a machine's own
//                           M code): once the controller shows Hold:0 after
//                           the message, press Cycle Start (`cyclestart`)
//                           after S seconds, as the operator at the machine
//                           does when the job is done by hand
//   --tool-change POLICY    CNCjs' M6 policy: `send` (default: the controller
//                           changes the tool, the line goes out as written)
//                           or `ignore` (CNCjs' own default: it comments the
//                           M6 out and pauses the job, and Resume goes on)
//
// WHEN is a line count N (once CNCjs has N of the program's lines
// acknowledged) or Ts, T seconds after the job started (e.g. 1.5s).
//
// Everything stays on 127.0.0.1: the server listens there on a port the
// system picks; its config, session store and home are a temporary
// directory, removed at the end.
'use strict';

const childProcess = require('child_process');
const crypto = require('crypto');
const fs = require('fs');
const os = require('os');
const path = require('path');

const io = require('socket.io-client');

const cncjsDir = path.dirname(require.resolve('cncjs/package.json'));
const cncjsVersion = require('cncjs/package.json').version;
// The token is signed with the jsonwebtoken CNCjs itself verifies with.
const jwt = require(require.resolve('jsonwebtoken', { paths: [cncjsDir] }));

function usage(msg) {
    process.stderr.write(`${msg}\nusage: node cncjs_run.js PORT PROGRAM [options] (see the head of this file)\n`);
    process.exit(2);
}

function parseWhen(text) {
    const m = /^(\d+(?:\.\d+)?)(s?)$/.exec(String(text).trim());
    if (!m) {
        usage(`bad WHEN: ${text}`);
    }
    return m[2] ? { seconds: Number(m[1]) } : { lines: Number(m[1]) };
}

const CLICKS = { '+10': 10, '10': 10, '-10': -10, '+1': 1, '1': 1, '-1': -1, '0': 0 };

function parseArgs(argv) {
    const opts = {
        timeout: 300,
        feedhold: null,
        holdFor: 0.5,
        overrides: [],
        jogs: [],
        resumeAfter: 0.5,
        operator: null,
        toolChange: 'send',
    };
    const positional = [];
    for (let i = 0; i < argv.length; i++) {
        const a = argv[i];
        const value = () => {
            if (i + 1 >= argv.length) {
                usage(`${a} needs a value`);
            }
            return argv[++i];
        };
        if (a === '--timeout') {
            opts.timeout = Number(value());
        } else if (a === '--feedhold') {
            opts.feedhold = parseWhen(value());
        } else if (a === '--hold-for') {
            opts.holdFor = Number(value());
        } else if (a === '--override') {
            const v = value();
            const at = v.lastIndexOf(':');
            if (at < 0) {
                usage(`--override WHEN:CLICKS, not ${v}`);
            }
            const clicks = v.slice(at + 1).split(',').map((c) => {
                if (!(c.trim() in CLICKS)) {
                    usage(`bad override click: ${c}`);
                }
                return CLICKS[c.trim()];
            });
            opts.overrides.push({ when: parseWhen(v.slice(0, at)), clicks, done: false });
        } else if (a === '--jog') {
            opts.jogs.push({ what: 'jog', line: value() });
        } else if (a === '--operator') {
            opts.operator = Number(value());
        } else if (a === '--console') {
            opts.jogs.push({ what: 'console', line: value() });
        } else if (a === '--resume-after') {
            const v = value();
            opts.resumeAfter = v === 'never' ? null : Number(v);
        } else if (a === '--tool-change') {
            opts.toolChange = value();
            if (!['send', 'ignore'].includes(opts.toolChange)) {
                usage(`--tool-change send|ignore, not ${opts.toolChange}`);
            }
        } else if (a.startsWith('--')) {
            usage(`unknown option ${a}`);
        } else {
            positional.push(a);
        }
    }
    if (positional.length !== 2) {
        usage('PORT and PROGRAM are needed');
    }
    [opts.port, opts.program] = positional;
    return opts;
}

const opts = parseArgs(process.argv.slice(2));
const programText = fs.readFileSync(opts.program, 'utf8');
const t0 = Date.now();
const now = () => (Date.now() - t0) / 1000;
const sleep = (ms) => new Promise((resolve) => setTimeout(resolve, ms));

// What CNCjs saw and did.
const seen = {
    cncjs: cncjsVersion,
    port: opts.port,
    program: path.basename(opts.program),
    read: [], // every `serialport:read` line, in order
    rx: [], // every line CNCjs read from the link (its own log, -vvv)
    written: [], // `serialport:write`: what CNCjs wrote for a command, with its bytes
    states: [], // the controller's states as CNCjs showed them, in order
    workflow: [], // CNCjs' workflow states, in order
    ok: 0, // `ok` lines read from the link
    errors: [], // `error:` lines
    alarms: [],
    actions: [], // what was pressed, when, in which state
    pauses: [], // the job paused by the program (M0/M1/M6) or by an error
    sender: null, // CNCjs' sender status: total, sent, received, ...
    ov: null, // the last `Ov:` (feed, rapids, spindle %)
    ov_seen: [], // every `Ov:` CNCjs showed, in order, with when it showed it
    mpos: null,
    state: null,
    finished: false,
    timed_out: false,
};

let controllerState = null; // the last `controller:state` status
let stateAt = 0; // seconds (now()) it came at
const operatorStops = []; // { t, msg }: stop messages for the operator read
let senderStatus = null;
let workflowState = null;
let jobStarted = null; // seconds (now()) the job started at
let settingsSeen = false;
let senderAtEnd = null; // the sender's status when the job ended

function stateName(status) {
    if (!status || !status.activeState) {
        return '';
    }
    // CNCjs parses `Hold:0` as activeState Hold, subState 0 (and any state
    // without a sub-state as sub-state 0 too).
    const sub = ['Hold', 'Door'].includes(status.activeState) ? `:${status.subState}` : '';
    return status.activeState + sub;
}

function record(what, extra) {
    seen.actions.push({ t: Number(now().toFixed(3)), what, state: stateName(controllerState),
        received: senderStatus ? senderStatus.received : 0, ...extra });
}

function hex(text) {
    // serialport writes a JavaScript string as its UTF-8 bytes.
    return Buffer.from(text, 'utf8').toString('hex').replace(/(..)(?!$)/g, '$1 ').toUpperCase();
}

// --- the server -----------------------------------------------------------

const home = fs.mkdtempSync(path.join(os.tmpdir(), 'cncjs-run-'));
const secret = crypto.randomBytes(24).toString('hex');
const configFile = path.join(home, 'cncrc.json');
fs.writeFileSync(configFile, JSON.stringify({
    secret,
    allowRemoteAccess: false,
    tool: { toolChangePolicy: opts.toolChange === 'send' ? 1 : 0 },
}, null, 2));

let server = null;
let serverLog = '';

function startServer() {
    return new Promise((resolve, reject) => {
        const bin = path.join(cncjsDir, 'bin', 'cncjs');
        server = childProcess.spawn(process.execPath, [
            bin, '--host', '127.0.0.1', '--port', '0', '--config', configFile,
            '--controller', 'Grbl', '-vvv',
        ], {
            cwd: home,
            // Its session store goes to $HOME/.cncjs-sessions: the temporary
            // directory, not the user's home.
            env: { ...process.env, HOME: home, USERPROFILE: home, FORCE_COLOR: '0', NODE_ENV: 'production' },
            stdio: ['ignore', 'pipe', 'pipe'],
        });
        let partial = '';
        const onData = (chunk) => {
            const text = partial + chunk.toString('utf8');
            const lines = text.split('\n');
            partial = lines.pop();
            for (const raw of lines) {
                // eslint-disable-next-line no-control-regex
                const line = raw.replace(/\x1b\[[0-9;]*m/g, '').replace(/\r$/, '');
                const started = /Starting the server at http:\/\/127\.0\.0\.1:(\d+)/.exec(line);
                if (started) {
                    resolve(Number(started[1]));
                }
                const rx = / silly controller:Grbl < (.*)$/.exec(line);
                if (rx) {
                    onLinkLine(rx[1]);
                } else if (!/ silly /.test(line)) {
                    serverLog += `${line}\n`;
                }
            }
        };
        server.stdout.on('data', onData);
        server.stderr.on('data', onData);
        server.on('exit', (code, signal) => {
            reject(new Error(`the CNCjs server ended (${code ?? signal}):\n${serverLog.slice(-4000)}`));
        });
    });
}

function onLinkLine(line) {
    seen.rx.push(line);
    if (line === 'ok') {
        seen.ok += 1;
    } else if (line.startsWith('error:')) {
        seen.errors.push(line);
    } else if (line.startsWith('ALARM:')) {
        seen.alarms.push(line);
    }
}

function stopServer() {
    return new Promise((resolve) => {
        if (!server || server.exitCode !== null || server.signalCode !== null) {
            resolve();
            return;
        }
        const kill = setTimeout(() => server.kill('SIGKILL'), 3000);
        server.removeAllListeners('exit');
        server.on('exit', () => {
            clearTimeout(kill);
            resolve();
        });
        server.kill('SIGTERM');
    });
}

// --- the client -------------------------------------------------------------

function connect(httpPort) {
    // As CNCjs' pendants do: a JWT signed with the config's secret, passed
    // as the socket.io query's `token`.
    const token = jwt.sign({ id: '', name: 'cncjs-pendant' }, secret, { expiresIn: '1h' });
    const socket = io.connect(`ws://127.0.0.1:${httpPort}`, { query: `token=${token}`, reconnection: false });
    socket.on('serialport:read', (line) => {
        const text = String(line).replace(/\r$/, '');
        seen.read.push(text);
        if (text.startsWith('[MSG:') && text.endsWith('then cycle start]')) {
            operatorStops.push({ t: now(), msg: text });
        }
    });
    socket.on('serialport:write', (data, context) => {
        seen.written.push({ t: Number(now().toFixed(3)), data, bytes: hex(data),
            source: context && context.source });
    });
    socket.on('controller:settings', (type, settings) => {
        if (settings && settings.settings && Object.keys(settings.settings).length > 0) {
            settingsSeen = true;
        }
    });
    socket.on('controller:state', (type, state) => {
        controllerState = state.status;
        stateAt = now();
        const name = stateName(controllerState);
        if (name && seen.states[seen.states.length - 1] !== name) {
            seen.states.push(name);
        }
        if (Array.isArray(controllerState.ov) && controllerState.ov.length) {
            seen.ov = controllerState.ov.map(Number);
            const last = seen.ov_seen[seen.ov_seen.length - 1];
            if (!last || last.ov.join() !== seen.ov.join()) {
                seen.ov_seen.push({ t: Number(now().toFixed(3)), ov: seen.ov });
            }
        }
        if (controllerState.mpos) {
            seen.mpos = ['x', 'y', 'z'].map((a) => Number(controllerState.mpos[a]));
        }
        seen.state = name;
    });
    socket.on('sender:status', (status) => {
        if (senderAtEnd) {
            return; // CNCjs rewinds its sender once the job has ended
        }
        senderStatus = status;
        const pause = seen.pauses[seen.pauses.length - 1];
        if (pause && pause.data === undefined && status.hold && status.holdReason) {
            pause.data = status.holdReason.data || null;
            pause.err = !!status.holdReason.err;
            pause.msg = status.holdReason.msg;
        }
        seen.sender = {
            total: status.total, sent: status.sent, received: status.received,
            hold: status.hold, holdReason: status.holdReason,
            elapsedTime: status.elapsedTime,
        };
    });
    socket.on('workflow:state', (state) => {
        if (state === 'paused' && workflowState !== 'paused') {
            // Why it paused comes with the sender's next status.
            seen.pauses.push({ t: Number(now().toFixed(3)), received: senderStatus ? senderStatus.received : 0 });
        }
        if (state === 'idle' && ['running', 'paused'].includes(workflowState)) {
            // The job ended (CNCjs' own `gcode:stop`): its sender's last
            // status, before the rewind that comes with the next one.
            senderAtEnd = senderStatus;
        }
        workflowState = state;
        if (seen.workflow[seen.workflow.length - 1] !== state) {
            seen.workflow.push(state);
        }
    });
    return socket;
}

function emitAck(socket, ...args) {
    return new Promise((resolve, reject) => {
        socket.emit(...args, (err, data) => (err ? reject(new Error(String(err.message || err))) : resolve(data)));
    });
}

async function waitFor(cond, seconds, what) {
    const deadline = Date.now() + seconds * 1000;
    while (!cond()) {
        if (Date.now() > deadline) {
            throw new Error(`no ${what} within ${seconds} s`);
        }
        await sleep(20);
    }
}

function due(when) {
    if (jobStarted === null) {
        return false;
    }
    if (when.seconds !== undefined) {
        return now() - jobStarted >= when.seconds;
    }
    return senderStatus !== null && senderStatus.received >= when.lines;
}

// The controller stopped: held at rest, or idle with nothing outstanding.
function atRest() {
    const name = stateName(controllerState);
    return name === 'Hold:0' || (name === 'Idle' && senderStatus && senderStatus.received >= senderStatus.sent);
}

async function run() {
    const httpPort = await startServer();
    seen.server = `127.0.0.1:${httpPort}`;
    const socket = connect(httpPort);
    await new Promise((resolve, reject) => {
        socket.on('connect', resolve);
        socket.on('error', (e) => reject(new Error(`socket.io: ${e}`)));
        socket.on('connect_error', (e) => reject(new Error(`socket.io: ${e}`)));
    });
    const port = opts.port;
    const command = (...args) => socket.emit('command', port, ...args);
    // As the Connection widget opens a port.
    await emitAck(socket, 'open', port, { controllerType: 'Grbl', baudrate: 115200, rtscts: false });
    record('open');
    // CNCjs is ready once it has a status report and the `$$` settings.
    await waitFor(() => settingsSeen && stateName(controllerState) === 'Idle', 30, 'Idle and settings after opening');
    record('ready');

    for (const { what, line } of opts.jogs) {
        const oks = seen.read.filter((l) => l === 'ok').length;
        record(what, { line });
        command('gcode', line);
        await waitFor(() => seen.read.filter((l) => l === 'ok' || l.startsWith('error:')).length > oks,
            30, `reply to ${line}`);
        await sleep(300);
        await waitFor(() => stateName(controllerState) === 'Idle', 60, `Idle after ${line}`);
    }

    // As the G-code widget's upload does (its HTTP API calls the same).
    const loaded = await emitAck(socket, 'command', port, 'gcode:load', seen.program, programText, {});
    seen.loaded = { total: loaded.total };
    record('gcode:start');
    command('gcode:start');
    jobStarted = now();

    let hold = null; // { at, held, done }
    let answered = 0; // operator stops answered with Cycle Start
    let pause = null; // the program pause being handled
    const deadline = opts.timeout;
    for (;;) {
        await sleep(20);
        if (now() > deadline) {
            seen.timed_out = true;
            break;
        }
        // Feed Hold, then Cycle Start once held (as the Grbl widget's buttons).
        if (opts.feedhold && !hold && due(opts.feedhold)) {
            record('feedhold');
            command('feedhold');
            hold = { at: now(), held: false };
        }
        if (hold && !hold.done) {
            hold.held = hold.held || stateName(controllerState) === 'Hold:0';
            const waited = now() - hold.at;
            if ((hold.held && waited >= opts.holdFor) || waited >= 10) {
                record('cyclestart', { hold_seen: hold.held });
                command('cyclestart');
                hold.done = true;
            }
        }
        for (const o of opts.overrides) {
            if (!o.done && due(o.when)) {
                for (const c of o.clicks) {
                    record('feedOverride', { value: c });
                    command('feedOverride', c);
                    await sleep(50);
                }
                o.done = true;
            }
        }
        // The job paused: by the program (M0/M1, M6 when ignored) or an error.
        // CNCjs may pause twice on one M0: when the line is read ahead but
        // does not fit the buffer, and again when Resume sends it.
        const last = seen.pauses[seen.pauses.length - 1];
        if (workflowState === 'paused' && last && last.data !== undefined && (!pause || pause.entry !== last)) {
            pause = { entry: last };
            if (last.err) {
                // An error paused the job: a user would stop and look.
                break;
            }
        }
        if (pause && !pause.done && opts.resumeAfter !== null) {
            // For M0/M1 the user waits for the machine to stop there (CNCjs
            // shows Hold:0); an M6 left out by CNCjs stops nothing.
            // It must stay so for the whole wait: a state CNCjs showed before
            // its next poll may be stale.
            const ready = pause.entry.data === 'M6' || atRest();
            if (!ready) {
                pause.readyAt = null;
            } else if (!pause.readyAt) {
                pause.readyAt = now();
                pause.entry.state = stateName(controllerState);
            }
            if (pause.readyAt && now() - pause.readyAt >= opts.resumeAfter) {
                record('gcode:resume', { pause: pause.entry.data });
                command('gcode:resume');
                pause.done = true;
            }
        }
        // A stop for the operator: Cycle Start once held there.
        const stop = operatorStops[answered];
        if (opts.operator !== null && stop && stateName(controllerState) === 'Hold:0'
            && stateAt > stop.t && now() - stop.t >= opts.operator) {
            record('cyclestart', { operator: stop.msg });
            command('cyclestart');
            answered += 1;
        }
        // CNCjs ends the job itself (`gcode:stop`) once every line is
        // acknowledged and the machine has been Idle for half a second.
        if (senderAtEnd && senderAtEnd.received < senderAtEnd.total) {
            break; // stopped short
        }
        if (senderAtEnd && (!hold || hold.done) && senderAtEnd.received >= senderAtEnd.total
            && stateName(controllerState) === 'Idle') {
            seen.finished = true;
            break;
        }
    }
    seen.t_end = Number(now().toFixed(3));
    // What was asked for and never came due before the end.
    seen.not_done = [];
    if (opts.feedhold && !hold) {
        seen.not_done.push('feedhold');
    }
    for (const o of opts.overrides.filter((x) => !x.done)) {
        seen.not_done.push(`override ${JSON.stringify(o.when)}`);
    }
    // One more status report for the final position and overrides.
    await sleep(600);
    record('close');
    await emitAck(socket, 'close', port).catch((e) => { seen.close_error = String(e.message); });
    socket.close();
}

// Killed (a test runner's timeout, Ctrl-C): the server goes with it.
for (const signal of ['SIGINT', 'SIGTERM', 'SIGHUP']) {
    process.on(signal, () => {
        if (server && server.exitCode === null) {
            server.kill('SIGKILL');
        }
        fs.rmSync(home, { recursive: true, force: true });
        process.exit(1);
    });
}

let failure = null;
run()
    .catch((e) => { failure = e; })
    .then(stopServer)
    .then(() => {
        fs.rmSync(home, { recursive: true, force: true });
        if (failure) {
            seen.error = String(failure.message || failure);
            seen.server_log = serverLog.split('\n').filter((l) => /error|warn/i.test(l)).slice(-30);
        }
        // Exit once the summary is out: to a pipe, a write is
        // asynchronous, and exiting at once cuts it at 64 KiB.
        process.stdout.write(`${JSON.stringify(seen)}\n`, () => process.exit(failure ? 1 : 0));
    });
