// A screenshot of a page in a running headless Chromium (web_test.sh starts one for all its shots:
// a browser's start-up costs seconds of CPU, a tab a fraction): opens URL in a new tab of the
// browser behind PROFILE/DevToolsActivePort, waits for the load event, as chromium --screenshot
// does, writes the viewport as OUT.png and closes the tab. Each shot is a fresh tab: a new document,
// nothing kept from the shot before. Node's own WebSocket (--experimental-websocket on Node 20).
// Usage: node --experimental-websocket web_shot.js PROFILE URL OUT.png WIDTH HEIGHT
'use strict';
const fs = require('fs'), path = require('path');
const [profile, url, out, width, height] = process.argv.slice(2);
const lines = fs.readFileSync(path.join(profile, 'DevToolsActivePort'), 'latin1').split('\n');
const ws = new WebSocket('ws://127.0.0.1:' + lines[0].trim() + lines[1].trim());
let next = 0;
const waiting = new Map(), events = [];
let onEvent = null;
function send(method, params, sessionId) {
    const id = ++next, msg = {id, method, params: params || {}};
    if (sessionId) msg.sessionId = sessionId;
    ws.send(JSON.stringify(msg));
    return new Promise((resolve, reject) => waiting.set(id, {resolve, reject, method}));
}
ws.onmessage = (e) => {
    const msg = JSON.parse(e.data);
    if (msg.id && waiting.has(msg.id)) {
        const w = waiting.get(msg.id);
        waiting.delete(msg.id);
        if (msg.error) w.reject(new Error(w.method + ': ' + msg.error.message)); else w.resolve(msg.result);
    } else if (msg.method) {
        events.push(msg);
        if (onEvent) onEvent();
    }
};
function event(method, sessionId) {
    return new Promise((resolve) => {
        const look = () => {
            const i = events.findIndex((m) => m.method === method && m.sessionId === sessionId);
            if (i >= 0) { onEvent = null; resolve(events.splice(i, 1)[0]); }
        };
        onEvent = look;
        look();
    });
}
ws.onerror = () => { console.error('web_shot: no browser at ' + profile); process.exit(1); };
ws.onopen = async () => {
    try {
        const {targetId} = await send('Target.createTarget', {url: 'about:blank'});
        const {sessionId} = await send('Target.attachToTarget', {targetId, flatten: true});
        await send('Page.enable', {}, sessionId);
        // The viewport of chromium --window-size=WIDTH,HEIGHT --screenshot, one pixel per CSS pixel.
        await send('Emulation.setDeviceMetricsOverride', {width: +width, height: +height, deviceScaleFactor: 1, mobile: false}, sessionId);
        events.length = 0;
        const nav = await send('Page.navigate', {url}, sessionId);
        if (nav.errorText) throw new Error(url + ': ' + nav.errorText);
        // The load event of this page, not of the tab's first about:blank.
        for (;;) {
            await event('Page.loadEventFired', sessionId);
            const r = await send('Runtime.evaluate', {expression: 'document.readyState + " " + location.href', returnByValue: true}, sessionId);
            const [state, href] = String(r.result.value).split(' ');
            if (state === 'complete' && href.split('#')[0] === url.split('#')[0]) break;
        }
        const shot = await send('Page.captureScreenshot', {format: 'png'}, sessionId);
        fs.writeFileSync(out, Buffer.from(shot.data, 'base64'));
        await send('Target.closeTarget', {targetId});
        ws.close();
        process.exit(0);
    } catch (e) {
        console.error('web_shot: ' + e.message);
        process.exit(1);
    }
};
