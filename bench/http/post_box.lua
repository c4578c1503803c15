-- wrk script: POST /v1/bodies with a small box (6 faces) on every request.
--   wrk -t2 -c8 -d10s -s bench/http/post_box.lua http://127.0.0.1:7878/v1/bodies
wrk.method = "POST"
wrk.body = '{"shape": {"type": "box", "size": [0.1, 0.1, 0.1]}}'
wrk.headers["Content-Type"] = "application/json"
