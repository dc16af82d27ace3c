// motorlab stub of NanoHTTPD 2.3.1 (org.nanohttpd, the FTC SDK's web server; written from its public
// signatures, no NanoHTTPD code). Compile-time only: on a robot the SDK's copy is used. See docs/ftc-robot.md.
package fi.iki.elonen;

import java.io.ByteArrayInputStream;
import java.io.InputStream;
import java.nio.charset.StandardCharsets;
import java.util.LinkedHashMap;
import java.util.List;
import java.util.Map;

public abstract class NanoHTTPD {
    public static final String MIME_PLAINTEXT = "text/plain";
    public static final String MIME_HTML = "text/html";

    public enum Method {
        GET, PUT, POST, DELETE, HEAD, OPTIONS, TRACE, CONNECT, PATCH
    }

    public interface IHTTPSession {
        Method getMethod();

        String getUri();

        Map<String, List<String>> getParameters();

        String getQueryParameterString();
    }

    public static class Response {
        public interface IStatus {
            String getDescription();

            int getRequestStatus();
        }

        public enum Status implements IStatus {
            OK(200, "OK"), BAD_REQUEST(400, "Bad Request"), NOT_FOUND(404, "Not Found"),
            INTERNAL_ERROR(500, "Internal Server Error");

            private final int requestStatus;
            private final String description;

            Status(int requestStatus, String description) {
                this.requestStatus = requestStatus;
                this.description = description;
            }

            @Override
            public String getDescription() {
                return requestStatus + " " + description;
            }

            @Override
            public int getRequestStatus() {
                return requestStatus;
            }
        }

        private final IStatus status;
        private final String mimeType;
        private final InputStream data;
        private final long contentLength;
        private final Map<String, String> headers = new LinkedHashMap<String, String>();

        protected Response(IStatus status, String mimeType, InputStream data, long totalBytes) {
            this.status = status;
            this.mimeType = mimeType;
            this.data = data;
            this.contentLength = totalBytes;
        }

        public void addHeader(String name, String value) {
            headers.put(name, value);
        }

        public String getHeader(String name) {
            return headers.get(name);
        }

        public IStatus getStatus() {
            return status;
        }

        public String getMimeType() {
            return mimeType;
        }

        public InputStream getData() {
            return data;
        }

        /** Not in NanoHTTPD's API (its length is private): for the stub's test server only. */
        public long stubContentLength() {
            return contentLength;
        }
    }

    public static final class ResponseException extends Exception {
        private static final long serialVersionUID = 1L;

        public ResponseException(Response.Status status, String message) {
            super(message);
        }
    }

    public static Response newFixedLengthResponse(Response.IStatus status, String mimeType, InputStream data,
                                                  long totalBytes) {
        return new Response(status, mimeType, data, totalBytes);
    }

    public static Response newFixedLengthResponse(Response.IStatus status, String mimeType, String txt) {
        byte[] bytes = txt == null ? new byte[0] : txt.getBytes(StandardCharsets.UTF_8);
        return newFixedLengthResponse(status, mimeType, new ByteArrayInputStream(bytes), bytes.length);
    }

    public static Response newChunkedResponse(Response.IStatus status, String mimeType, InputStream data) {
        return new Response(status, mimeType, data, -1);
    }
}
