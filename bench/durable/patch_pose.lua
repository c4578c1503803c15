-- wrk script: PATCH the pose of one body, a new position each request.
wrk.method = "PATCH"
wrk.headers["Content-Type"] = "application/json"
local n = 0
request = function()
    n = n + 1
    local body = string.format('{"pose":{"position":[%d,0,0],"rotation":[0,0,0,1]}}', n)
    return wrk.format(nil, nil, nil, body)
end
