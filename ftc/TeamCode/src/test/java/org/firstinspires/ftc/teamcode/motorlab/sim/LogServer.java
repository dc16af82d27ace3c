package org.firstinspires.ftc.teamcode.motorlab.sim;

import com.qualcomm.robotcore.util.WebHandlerManager;
import com.sun.net.httpserver.HttpExchange;
import com.sun.net.httpserver.HttpServer;

import org.firstinspires.ftc.robotcore.internal.webserver.WebHandler;
import org.firstinspires.ftc.teamcode.motorlab.MotorlabLogFiles;

import java.io.File;
import java.io.IOException;
import java.io.InputStream;
import java.io.OutputStream;
import java.io.UnsupportedEncodingException;
import java.net.InetSocketAddress;
import java.net.URLDecoder;
import java.util.ArrayList;
import java.util.Collections;
import java.util.HashMap;
import java.util.List;
import java.util.Map;

import fi.iki.elonen.NanoHTTPD;

/**
 * Serves {@link MotorlabLogFiles}' handlers on 127.0.0.1 the way the robot controller's web server does
 * (exact URIs, a NanoHTTPD session per request), for tests/test_ftc_robot.py: {@code LogServer FOLDER SECONDS}
 * prints the port, serves FOLDER, and stops after SECONDS.
 */
public final class LogServer {
    private LogServer() {
    }

    static final class Manager implements WebHandlerManager {
        final Map<String, WebHandler> handlers = new HashMap<String, WebHandler>();

        @Override
        public void register(String command, WebHandler webHandler) {
            handlers.put(command, webHandler);
        }

        @Override
        public WebHandler getRegistered(String command) {
            return handlers.get(command);
        }
    }

    static Map<String, List<String>> parameters(String query) throws UnsupportedEncodingException {
        Map<String, List<String>> out = new HashMap<String, List<String>>();
        if (query == null) {
            return out;
        }
        for (String pair : query.split("&")) {
            int eq = pair.indexOf('=');
            String key = URLDecoder.decode(eq < 0 ? pair : pair.substring(0, eq), "UTF-8");
            String value = eq < 0 ? "" : URLDecoder.decode(pair.substring(eq + 1), "UTF-8");
            if (!out.containsKey(key)) {
                out.put(key, new ArrayList<String>());
            }
            out.get(key).add(value);
        }
        return out;
    }

    static void serve(Manager manager, HttpExchange exchange) throws IOException {
        final String uri = exchange.getRequestURI().getPath();
        final String query = exchange.getRequestURI().getRawQuery();
        final Map<String, List<String>> params = parameters(query);
        NanoHTTPD.IHTTPSession session = new NanoHTTPD.IHTTPSession() {
            @Override
            public NanoHTTPD.Method getMethod() {
                return NanoHTTPD.Method.GET;
            }

            @Override
            public String getUri() {
                return uri;
            }

            @Override
            public Map<String, List<String>> getParameters() {
                return Collections.unmodifiableMap(params);
            }

            @Override
            public String getQueryParameterString() {
                return query;
            }
        };
        WebHandler handler = manager.getRegistered(uri);
        try {
            if (handler == null) {
                exchange.sendResponseHeaders(404, -1);
                return;
            }
            NanoHTTPD.Response response = handler.getResponse(session);
            exchange.getResponseHeaders().add("Content-Type", response.getMimeType());
            long length = response.stubContentLength();
            exchange.sendResponseHeaders(response.getStatus().getRequestStatus(), length == 0 ? -1 : length);
            try (InputStream in = response.getData(); OutputStream out = exchange.getResponseBody()) {
                byte[] buffer = new byte[8192];
                for (int n = in.read(buffer); n > 0; n = in.read(buffer)) {
                    out.write(buffer, 0, n);
                }
            }
        } catch (NanoHTTPD.ResponseException e) {
            exchange.sendResponseHeaders(500, -1);
        } finally {
            exchange.close();
        }
    }

    public static void main(String[] args) throws Exception {
        final Manager manager = new Manager();
        MotorlabLogFiles.register(manager, new File(args[0]));
        HttpServer server = HttpServer.create(new InetSocketAddress("127.0.0.1", 0), 0);
        server.createContext("/", exchange -> serve(manager, exchange));
        server.start();
        System.out.println(server.getAddress().getPort());
        System.out.flush();
        Thread.sleep((long) (Double.parseDouble(args[1]) * 1000));
        server.stop(0);
    }
}
