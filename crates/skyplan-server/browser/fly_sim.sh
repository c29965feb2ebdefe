#!/usr/bin/env bash
# What the second flight browser test runs: `skyplan fly --sim` with its live view on ADDR ($1),
# the simulator at SPEED× real time ($2), the default route across the city.
exec "${SKYPLAN_BIN:?set SKYPLAN_BIN to the skyplan binary}" fly --sim --speedup "$2" --view "$1"
