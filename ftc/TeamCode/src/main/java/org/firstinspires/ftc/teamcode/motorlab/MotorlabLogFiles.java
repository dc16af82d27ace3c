package org.firstinspires.ftc.teamcode.motorlab;

import android.content.Context;

import com.qualcomm.robotcore.util.WebHandlerManager;

import org.firstinspires.ftc.ftccommon.external.WebHandlerRegistrar;
import org.firstinspires.ftc.robotcore.internal.system.AppUtil;
import org.firstinspires.ftc.robotcore.internal.webserver.WebHandler;

import java.io.File;
import java.io.FileInputStream;
import java.io.IOException;
import java.util.ArrayList;
import java.util.Arrays;
import java.util.Comparator;
import java.util.List;

import fi.iki.elonen.NanoHTTPD;

/**
 * Serves the motorlab OpModes' logs on the robot controller's web server (port 8080), so that
 * {@code motorlab robot pull} brings them home over Wi-Fi (docs/robot.md):
 *
 * <ul>
 *   <li>{@code GET /motorlab/logs}: JSON {@code {"folder": "...", "files": [{"name", "bytes", "modified_ms"}]}},
 *       newest first;</li>
 *   <li>{@code GET /motorlab/logs/download?file=NAME}: the file, with its length.</li>
 * </ul>
 *
 * The SDK calls {@link #registerRoutes} when its web server is created ({@code @WebHandlerRegistrar}: a
 * public static method taking a {@code Context} and a {@code WebHandlerManager}), as Road Runner's
 * {@code FileServing.kt} does for its tuning files. Only plain file names in the log folder are served.
 */
public final class MotorlabLogFiles {
    public static final String LIST = "/motorlab/logs";
    public static final String DOWNLOAD = "/motorlab/logs/download";

    private MotorlabLogFiles() {
    }

    /** The folder the OpModes write to ({@code DynoConfig.folder} under {@code AppUtil.FIRST_FOLDER}). */
    public static File folder() {
        return new File(AppUtil.FIRST_FOLDER, new DynoConfig().folder);
    }

    @WebHandlerRegistrar
    public static void registerRoutes(Context context, WebHandlerManager manager) {
        register(manager, folder());
    }

    /** Register both routes for {@code folder} (the tests serve a temporary folder). */
    public static void register(WebHandlerManager manager, File folder) {
        manager.register(LIST, listHandler(folder));
        manager.register(DOWNLOAD, downloadHandler(folder));
    }

    static File[] logs(File folder) {
        File[] files = folder.listFiles();
        if (files == null) {
            return new File[0];
        }
        List<File> kept = new ArrayList<File>();
        for (File f : files) {
            if (f.isFile()) {
                kept.add(f);
            }
        }
        File[] plain = kept.toArray(new File[0]);
        Arrays.sort(plain, new Comparator<File>() {
            @Override
            public int compare(File a, File b) {
                return Long.compare(b.lastModified(), a.lastModified());
            }
        });
        return plain;
    }

    static String json(String text) {
        StringBuilder out = new StringBuilder("\"");
        for (char c : text.toCharArray()) {
            if (c == '"' || c == '\\') {
                out.append('\\').append(c);
            } else if (c < 0x20) {
                out.append(String.format("\\u%04x", (int) c));
            } else {
                out.append(c);
            }
        }
        return out.append('"').toString();
    }

    static WebHandler listHandler(final File folder) {
        return new WebHandler() {
            @Override
            public NanoHTTPD.Response getResponse(NanoHTTPD.IHTTPSession session) {
                StringBuilder sb = new StringBuilder("{\"folder\": ").append(json(folder.getPath()))
                        .append(", \"files\": [");
                File[] files = logs(folder);
                for (int i = 0; i < files.length; i++) {
                    sb.append(i == 0 ? "" : ", ").append("{\"name\": ").append(json(files[i].getName()))
                            .append(", \"bytes\": ").append(files[i].length())
                            .append(", \"modified_ms\": ").append(files[i].lastModified()).append('}');
                }
                sb.append("]}");
                return NanoHTTPD.newFixedLengthResponse(NanoHTTPD.Response.Status.OK, "application/json",
                        sb.toString());
            }
        };
    }

    static WebHandler downloadHandler(final File folder) {
        return new WebHandler() {
            @Override
            public NanoHTTPD.Response getResponse(NanoHTTPD.IHTTPSession session) throws IOException {
                List<String> names = session.getParameters().get("file");
                String name = names == null || names.size() != 1 ? "" : names.get(0);
                if (name.isEmpty() || name.contains("/") || name.contains("\\") || name.startsWith(".")) {
                    return NanoHTTPD.newFixedLengthResponse(NanoHTTPD.Response.Status.BAD_REQUEST,
                            NanoHTTPD.MIME_PLAINTEXT, "give one file=NAME of " + LIST);
                }
                File file = new File(folder, name);
                if (!file.isFile()) {
                    return NanoHTTPD.newFixedLengthResponse(NanoHTTPD.Response.Status.NOT_FOUND,
                            NanoHTTPD.MIME_PLAINTEXT, "no log named " + name);
                }
                return NanoHTTPD.newFixedLengthResponse(NanoHTTPD.Response.Status.OK, NanoHTTPD.MIME_PLAINTEXT,
                        new FileInputStream(file), file.length());
            }
        };
    }
}
