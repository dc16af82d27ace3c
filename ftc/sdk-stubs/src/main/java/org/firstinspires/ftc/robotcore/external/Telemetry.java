// motorlab stub of the FTC SDK API (written from its public signatures; no SDK code). Compile-time only:
// on a robot the real SDK class is used. See docs/ftc-robot.md.
package org.firstinspires.ftc.robotcore.external;

/** Stub: the data/line/update subset of Telemetry (no Func producers, actions, speech or log). */
public interface Telemetry {
    Item addData(String caption, String format, Object... args);

    Item addData(String caption, Object value);

    void clear();

    void clearAll();

    boolean update();

    Line addLine();

    Line addLine(String lineCaption);

    boolean isAutoClear();

    void setAutoClear(boolean autoClear);

    int getMsTransmissionInterval();

    void setMsTransmissionInterval(int msTransmissionInterval);

    interface Line {
        Item addData(String caption, String format, Object... args);

        Item addData(String caption, Object value);
    }

    interface Item {
        String getCaption();

        Item setCaption(String caption);

        Item setValue(String format, Object... args);

        Item setValue(Object value);

        Item setRetained(Boolean retained);

        boolean isRetained();

        Item addData(String caption, String format, Object... args);

        Item addData(String caption, Object value);
    }
}
