-- wrk script: GET /v1/spatial/sphere about a different centre on every request, spread
-- uniformly over a city of boxes (see bench/http/spatial.sh, which lays the city out).
--
--   wrk -t2 -c8 -d10s --latency -s bench/http/spatial.lua http://127.0.0.1:7878
--
-- Environment: SPATIAL_EXTENT (the city's side, meters; default 2000), SPATIAL_HEIGHT
-- (centres' z range, meters; default 60), SPATIAL_RADIUS (meters; default 15),
-- SPATIAL_DETAIL (bodies, features or portions; default features).
local extent = tonumber(os.getenv("SPATIAL_EXTENT") or "2000")
local height = tonumber(os.getenv("SPATIAL_HEIGHT") or "60")
local radius = tonumber(os.getenv("SPATIAL_RADIUS") or "15")
local detail = os.getenv("SPATIAL_DETAIL") or "features"

local threads = 0

function setup(thread)
    threads = threads + 1
    thread:set("seed", threads)
end

function init(args)
    -- One fixed sequence of centres per thread: runs are repeatable.
    math.randomseed(1000 + seed)
end

function request()
    local x = math.random() * extent
    local y = math.random() * extent
    local z = math.random() * height
    local path = string.format(
        "/v1/spatial/sphere?x=%.3f&y=%.3f&z=%.3f&r=%g&detail=%s",
        x, y, z, radius, detail)
    return wrk.format("GET", path)
end
