#!/usr/bin/env python3
"""A TCP relay that delivers each chunk it reads from the client `--delay_ms` later (the server's
answers pass at once): the latency `tc qdisc ... netem delay` adds on the learner's egress, for
kernels built without sch_netem. Chunks keep their order and stay in flight together, so it delays
without limiting throughput.

    delay_proxy.py --listen 127.0.0.1:PORT --to HOST:PORT --delay_ms 20
"""
import argparse
import asyncio
import sys
import time


async def delayed_pump(reader, writer, delay_s):
    queue = asyncio.Queue()

    async def deliver():
        while True:
            due, chunk = await queue.get()
            if chunk is None:
                break
            wait = due - time.monotonic()
            if wait > 0:
                await asyncio.sleep(wait)
            writer.write(chunk)
            await writer.drain()

    delivery = asyncio.ensure_future(deliver())
    try:
        while True:
            chunk = await reader.read(1 << 16)
            if not chunk:
                break
            queue.put_nowait((time.monotonic() + delay_s, chunk))
    finally:
        queue.put_nowait((0, None))
        try:
            await delivery
        finally:
            writer.close()


async def pump(reader, writer):
    try:
        while True:
            chunk = await reader.read(1 << 16)
            if not chunk:
                break
            writer.write(chunk)
            await writer.drain()
    finally:
        writer.close()


async def relay(client_reader, client_writer, target, delay_s):
    host, port = target
    try:
        server_reader, server_writer = await asyncio.open_connection(host, port)
    except OSError:
        client_writer.close()
        return
    await asyncio.gather(delayed_pump(client_reader, server_writer, delay_s),
                         pump(server_reader, client_writer), return_exceptions=True)


def address(text):
    host, _, port = text.rpartition(":")
    if not host or not port.isdigit():
        raise argparse.ArgumentTypeError(f"'{text}' is not HOST:PORT")
    return host, int(port)


async def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--listen", type=address, required=True)
    parser.add_argument("--to", type=address, required=True)
    parser.add_argument("--delay_ms", type=float, required=True)
    args = parser.parse_args()
    if not 0 <= args.delay_ms <= 10000:
        sys.exit("error: --delay_ms must be in [0, 10000]")
    server = await asyncio.start_server(
        lambda r, w: relay(r, w, args.to, args.delay_ms / 1000), args.listen[0], args.listen[1])
    print(f"delaying {args.listen[0]}:{args.listen[1]} -> {args.to[0]}:{args.to[1]} by {args.delay_ms} ms",
          flush=True)
    async with server:
        await server.serve_forever()


if __name__ == "__main__":
    asyncio.run(main())
