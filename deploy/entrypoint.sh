#!/bin/sh
# Start the dashboard with basic auth on. Secrets come from the environment or from files
# (e.g. Docker secrets), never from the image:
#   TUNNELSETTLE_USERS_FILE     JSON file {"user": "password", ...} (default /run/secrets/users.json)
#   TUNNELSETTLE_COOKIE_SECRET  at least 32 characters, or TUNNELSETTLE_COOKIE_SECRET_FILE
#   TUNNELSETTLE_ORIGIN         host[:port] the browser uses (the reverse proxy's), for the websocket
#   TUNNELSETTLE_PREFIX         URL prefix under the proxy (optional)
#   TUNNELSETTLE_PROCESSES      panel serve --num-procs (default 1)
set -eu
USERS_FILE="${TUNNELSETTLE_USERS_FILE:-/run/secrets/users.json}"
if [ -z "${TUNNELSETTLE_COOKIE_SECRET:-}" ] && [ -n "${TUNNELSETTLE_COOKIE_SECRET_FILE:-}" ]; then
    TUNNELSETTLE_COOKIE_SECRET="$(cat "$TUNNELSETTLE_COOKIE_SECRET_FILE")"
fi
export TUNNELSETTLE_COOKIE_SECRET="${TUNNELSETTLE_COOKIE_SECRET:-}"
if [ -z "${TUNNELSETTLE_ORIGIN:-}" ]; then
    echo "TUNNELSETTLE_ORIGIN is not set: give the host[:port] the browser uses" >&2
    exit 2
fi
set -- --address 0.0.0.0 --port 5006 --basic-auth "$USERS_FILE" \
    --allow-websocket-origin "$TUNNELSETTLE_ORIGIN" \
    --num-procs "${TUNNELSETTLE_PROCESSES:-1}" "$@"
if [ -n "${TUNNELSETTLE_PREFIX:-}" ]; then
    set -- --prefix "$TUNNELSETTLE_PREFIX" "$@"
fi
exec tunnelsettle serve "$@"
